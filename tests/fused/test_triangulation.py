import numpy as np
import pytest

from pedenv.config import FusedConfig
from pedenv.fused.history import TORSO_KEYPOINTS, TrackHistory
from pedenv.fused.triangulation import triangulation_cue
from pedenv.geometry import pixel_rays

from fused_frames import make_frame

ANGLE_STD = 3.0 / 1266.0


def observe(ground, ego_xs, times, pitch=0.0):
    """Torso rays of pedestrians at ``ground`` seen from an ego at x = each of ``ego_xs``."""
    out = []
    for x, t in zip(ego_xs, times):
        f = make_frame(ground, pitch=pitch, ego_xyz=(x, 0.0, 0.0), timestamp=t)
        rays = pixel_rays(f.detections.keypoints, f.camera.intrinsics, f.cam_to_world)[:, TORSO_KEYPOINTS]
        out.append((rays, np.ones(rays.shape[:2], bool), f.cam_to_world[:3, 3], t))
    return out


def run(observations, config=FusedConfig()):
    *past, now = observations
    n = now[0].shape[0]
    hist = TrackHistory(config.history_length)
    hist.carry(np.full(n, -1))
    rows = np.arange(n)
    for rays, usable, origin, t in past:
        hist.push(rows, rays, usable, origin, t)
    rays, usable, origin, t = now
    return triangulation_cue(rays, usable, origin, t, hist.rays, hist.usable, hist.origins, hist.times,
                             hist.filled, ANGLE_STD, config)


def test_standing_pedestrians_from_a_driving_pitched_ego():
    ground = np.array([[25.0, 4.0, 0.3], [30.0, -6.0, -0.2]])
    obs = observe(ground, ego_xs=np.arange(6) * 1.4, times=np.arange(6) * 0.1, pitch=0.02)
    cue = run(obs)
    assert cue.valid.all()
    np.testing.assert_allclose(cue.positions, ground[:, :2], atol=0.05)
    ranges = np.linalg.norm(ground[:, :2] - [7.0, 0.0], axis=1)
    # a pedestrian who may have walked (default) leaves the range loose, one known to stand does not
    sd_walk = np.sqrt(np.linalg.eigvalsh(cue.covariances)[:, 1])
    still = run(obs, FusedConfig(pedestrian_speed_std_mps=0.0, lateral_std_m=0.0))
    sd_still = np.sqrt(np.linalg.eigvalsh(still.covariances)[:, 1])
    assert np.all(sd_still < 0.06 * ranges)
    assert np.all(sd_walk > 2 * sd_still)


def test_more_baseline_tightens_the_estimate():
    ground = np.array([[30.0, 5.0, 0.0]])
    still = FusedConfig(pedestrian_speed_std_mps=0.0)
    short = run(observe(ground, ego_xs=[0.0, 2.5], times=[0.0, 0.1]), still)
    long = run(observe(ground, ego_xs=np.linspace(0.0, 5.0, 8), times=np.arange(8) * 0.1), still)
    assert short.valid[0] and long.valid[0]
    assert np.linalg.det(long.covariances[0]) < np.linalg.det(short.covariances[0])


def test_a_possible_walker_leaves_the_range_as_loose_as_the_drift_over_the_parallax():
    # the drift of a walker moves all past rays together: more rays do not average it out
    ground = np.array([[30.0, 5.0, 0.0]])
    obs = observe(ground, ego_xs=np.linspace(0.0, 5.0, 8), times=np.arange(8) * 0.1)
    cue = run(obs, FusedConfig(pedestrian_speed_std_mps=0.8))
    ray_now = ground[0, :2] - [5.0, 0.0]
    ray_then = ground[0, :2] - [0.0, 0.0]
    sin = abs(np.cross(ray_now, ray_then)) / (np.linalg.norm(ray_now) * np.linalg.norm(ray_then))
    sd_along = np.sqrt(np.linalg.eigvalsh(cue.covariances[0])[1])
    assert sd_along >= 0.9 * 0.8 * 0.7 / sin


def test_outlier_ray_is_dropped():
    ground = np.array([[20.0, 4.0, 0.0]])
    obs = observe(ground, ego_xs=np.linspace(0.0, 4.0, 6), times=np.arange(6) * 0.1)
    rays, usable, origin, t = obs[2]
    bent = rays.copy()
    bent[..., 1] += 0.2  # a wrong detection in one past frame
    obs[2] = (bent / np.linalg.norm(bent, axis=-1, keepdims=True), usable, origin, t)
    cue = run(obs)
    np.testing.assert_allclose(cue.positions, ground[:, :2], atol=0.1)


@pytest.mark.parametrize("ego_xs, times, reason", [
    ([0.0], [0.0], "no-history"),
    ([0.0, 0.0, 0.05], [0.0, 0.1, 0.2], "no-baseline"),
])
def test_triangulation_declines(ego_xs, times, reason):
    cue = run(observe(np.array([[20.0, 3.0, 0.0]]), ego_xs=ego_xs, times=times))
    assert not cue.valid[0] and cue.reasons[0] == reason


def test_no_parallax_straight_ahead():
    # a pedestrian straight ahead on the ego's line of travel: the rays stay parallel
    config = FusedConfig(min_parallax_rad=0.05)
    cue = run(observe(np.array([[40.0, 0.0, 0.0]]), ego_xs=[0.0, 1.0], times=[0.0, 0.1]), config)
    assert not cue.valid[0] and cue.reasons[0] == "no-parallax"


def test_history_carries_with_the_tracker_rows():
    hist = TrackHistory(3)
    hist.carry(np.array([-1, -1]))
    hist.push(np.array([0, 1]), np.ones((2, 4, 3)), np.ones((2, 4), bool), np.zeros(3), 0.0)
    hist.push(np.array([1]), 2 * np.ones((1, 4, 3)), np.ones((1, 4), bool), np.ones(3), 0.1)
    hist.carry(np.array([1, -1]))  # row 1 survives as row 0, a new track at row 1
    assert hist.filled.tolist() == [[True, True, False], [False, False, False]]
    assert hist.times[0, :2].tolist() == [0.1, 0.0]
