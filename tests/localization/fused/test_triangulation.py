import numpy as np
import pytest

from pedenv.config import FusedConfig
from pedenv.localization.fused import triangulation
from pedenv.localization.fused.history import TrackHistory, ray_terms
from pedenv.localization.fused.triangulation import RaysNow, triangulate, triangulation_cue

from fused_frames import make_frame, skeletons_of


def observe(ground, ego_xs, times, pitch=0.0):
    """Skeletons of pedestrians at ``ground`` seen from an ego at x = each of ``ego_xs``."""
    return [(skeletons_of(make_frame(ground, pitch=pitch, ego_xyz=(x, 0.0, 0.0), timestamp=t)), t)
            for x, t in zip(ego_xs, times)]


DEFAULT_FUSED = FusedConfig()


def run(observations, config=DEFAULT_FUSED, start=None, tri=False):
    """The triangulation cue of the last observation over the others; ``start``: (N, 2) the
    believed ground points (default: the truth is unknown, the last skeleton's mean height cut)."""
    *past, (now, t) = observations
    n = len(now)
    hist = TrackHistory(config.history_length)
    hist.carry(np.full(n, -1))
    rows = np.arange(n)
    for skel, time in past:
        terms, dots = ray_terms(skel.rays, skel.origin)
        hist.push(rows, skel.rays, terms, dots, skel.usable, skel.origin, time)
    r = np.linalg.norm(np.asarray(start, float) - now.origin[:2], axis=1)
    begin = now.origin + (r[:, None] / now.horizontal)[..., None] * now.rays
    terms, _ = ray_terms(now.rays, now.origin)
    result = triangulate(RaysNow(now.rays, terms, now.usable, now.origin, t, now.angle_std), begin, np.ones(n, bool),
                         hist.of(rows))
    return result if tri else triangulation_cue(result, now)


def total(cue):
    return cue.covariances + cue.bias_covariances


def still_walkers(monkeypatch, lateral=True):
    """The cue's model with no walker drift (and, ``lateral`` False, no sideways body spread)."""
    monkeypatch.setattr(triangulation, "PEDESTRIAN_SPEED_STD_MPS", 0.0)
    if not lateral:
        monkeypatch.setattr(triangulation, "LATERAL_STD_M", 0.0)


def test_standing_pedestrians_from_a_driving_pitched_ego(monkeypatch):
    ground = np.array([[25.0, 4.0, 0.3], [30.0, -6.0, -0.2]])
    obs = observe(ground, ego_xs=np.arange(6) * 1.4, times=np.arange(6) * 0.1, pitch=0.02)
    cue = run(obs, start=ground[:, :2] * 1.05)
    assert cue.valid.all()
    np.testing.assert_allclose(cue.positions, ground[:, :2], atol=0.05)
    ranges = np.linalg.norm(ground[:, :2] - [7.0, 0.0], axis=1)
    # a pedestrian who may have walked (default) leaves the range loose, one known to stand does not
    sd_walk = np.sqrt(np.linalg.eigvalsh(total(cue))[:, 1])
    still_walkers(monkeypatch, lateral=False)
    still = run(obs, start=ground[:, :2])
    sd_still = np.sqrt(np.linalg.eigvalsh(total(still))[:, 1])
    assert np.all(sd_still < 0.06 * ranges)
    assert np.all(sd_walk > 2 * sd_still)
    # the pixel noise is new every frame; the walker's drift repeats: it is the per-person part
    assert np.allclose(still.bias_covariances, 0.0)
    assert np.all(np.linalg.eigvalsh(cue.bias_covariances)[:, 1] > np.linalg.eigvalsh(cue.covariances)[:, 1])


def test_more_baseline_tightens_the_estimate(monkeypatch):
    ground = np.array([[30.0, 5.0, 0.0]])
    still_walkers(monkeypatch)
    still = FusedConfig(history_length=10)
    short = run(observe(ground, ego_xs=[0.0, 2.5], times=[0.0, 0.1]), still, start=ground[:, :2])
    long = run(observe(ground, ego_xs=np.linspace(0.0, 5.0, 8), times=np.arange(8) * 0.1), still, start=ground[:, :2])
    assert short.valid[0] and long.valid[0]
    assert np.linalg.det(long.covariances[0]) < np.linalg.det(short.covariances[0])


def test_a_possible_walker_leaves_the_range_as_loose_as_the_drift_over_the_parallax():
    # the drift of a walker moves all past rays together: more rays do not average it out
    ground = np.array([[30.0, 5.0, 0.0]])
    obs = observe(ground, ego_xs=np.linspace(0.0, 5.0, 8), times=np.arange(8) * 0.1)
    assert triangulation.PEDESTRIAN_SPEED_STD_MPS == 0.8
    cue = run(obs, FusedConfig(history_length=10), start=ground[:, :2])
    ray_now = ground[0, :2] - [5.0, 0.0]
    ray_then = ground[0, :2] - [0.0, 0.0]
    sin = abs(np.cross(ray_now, ray_then)) / (np.linalg.norm(ray_now) * np.linalg.norm(ray_then))
    sd_along = np.sqrt(np.linalg.eigvalsh(total(cue)[0])[1])
    assert sd_along >= 0.85 * 0.8 * 0.7 / sin


def test_outlier_ray_is_dropped():
    from dataclasses import replace
    ground = np.array([[20.0, 4.0, 0.0]])
    obs = observe(ground, ego_xs=np.linspace(0.0, 4.0, 6), times=np.arange(6) * 0.1)
    skel, t = obs[2]
    bent = skel.rays.copy()
    bent[..., 1] += 0.2  # a wrong detection in one past frame
    obs[2] = (replace(skel, rays=bent / np.linalg.norm(bent, axis=-1, keepdims=True)), t)
    cue = run(obs, start=ground[:, :2] * 1.05)
    np.testing.assert_allclose(cue.positions, ground[:, :2], atol=0.1)


@pytest.mark.parametrize("ego_xs, times, reason", [
    ([0.0], [0.0], "no-history"),
    ([0.0, 0.0, 0.05], [0.0, 0.1, 0.2], "no-baseline"),
])
def test_triangulation_declines(ego_xs, times, reason):
    ground = np.array([[20.0, 3.0, 0.0]])
    cue = run(observe(ground, ego_xs=ego_xs, times=times), start=ground[:, :2])
    assert not cue.valid[0] and cue.reason_names[0] == reason


def test_no_parallax_straight_ahead(monkeypatch):
    # a pedestrian straight ahead on the ego's line of travel: the rays stay parallel
    monkeypatch.setattr(triangulation, "MIN_PARALLAX_RAD", 0.05)
    ground = np.array([[40.0, 0.0, 0.0]])
    cue = run(observe(ground, ego_xs=[0.0, 1.0], times=[0.0, 0.1]), start=ground[:, :2])
    assert not cue.valid[0] and cue.reason_names[0] == "no-parallax"


def test_every_keypoint_of_a_standing_person_is_triangulated(monkeypatch):
    ground = np.array([[15.0, 4.0, 0.0]])
    frames = [make_frame(ground, ego_xyz=(x, 0.0, 0.0), timestamp=0.1 * i) for i, x in enumerate(np.arange(6) * 0.8)]
    still_walkers(monkeypatch)
    tri = run([(skeletons_of(f), f.timestamp) for f in frames], start=ground[:, :2], tri=True)
    from fused_frames import upright_skeletons
    assert tri.good.all()
    np.testing.assert_allclose(tri.points, upright_skeletons(ground, [1.72]), atol=0.02)


def test_history_carries_with_the_tracker_rows():
    hist = TrackHistory(3)
    hist.carry(np.array([-1, -1]))
    rays = np.zeros((2, 17, 3))
    rays[..., 0] = 1.0
    terms, dots = ray_terms(rays, np.zeros(3))
    hist.push(np.array([0, 1]), rays, terms, dots, np.ones((2, 17), bool), np.zeros(3), 0.0)
    hist.push(np.array([1]), rays[:1], terms[:1], dots[:1], np.ones((1, 17), bool), np.ones(3), 0.1)
    hist.carry(np.array([1, -1]))  # row 1 survives as row 0, a new track at row 1
    assert hist.filled.sum(axis=1).tolist() == [2, 0]
    assert sorted(hist.cameras[0, hist.filled[0], 4].tolist()) == [0.0, 0.1]
    assert hist.count.tolist() == [2, 0]
