import numpy as np
import pytest

from pedenv.config import Config, FusedConfig
from pedenv.localization.fused.body_height import (
    GATE_SIGMAS,
    add_measurements,
    height_measurements,
    prior_std,
    track_heights,
)
from pedenv.localization.fused.cue import CueEstimate, range_bearing_covariance
from pedenv.model import PedestrianEnvironmentModel

from fused_frames import make_frame

ORIGIN = np.array([0.0, 0.0, 1.5])


def cue(name, ranges, frame_std, bias_std=0.0):
    """A cue placing people straight ahead (+x) at ``ranges`` with spreads along the ray (metres)."""
    r = np.asarray(ranges, float)
    bearing = np.tile([1.0, 0.0], (len(r), 1))
    frame = range_bearing_covariance(bearing, np.full(len(r), frame_std**2), 0.01)
    bias = range_bearing_covariance(bearing, np.full(len(r), bias_std**2), 0.01)
    return CueEstimate(name, bearing * r[:, None], frame, bias, np.ones(len(r), bool), np.zeros(len(r), np.int64))


def test_the_prior_spread_holds_heights_and_posture():
    config = FusedConfig()
    assert prior_std(config) == pytest.approx(np.hypot(0.09, 0.017 * 1.72))
    mean, std = track_heights(np.zeros((3, 2, 3)), config)
    np.testing.assert_allclose(mean, 1.72)
    np.testing.assert_allclose(std, prior_std(config))


@pytest.mark.parametrize("ground_range, expected", [(10.0, 1.72), (7.0, 1.204), (11.5, 1.978)])
def test_a_cue_that_needs_no_height_measures_it(ground_range, expected):
    # the height cue put them 10 m away at 1.72 m: a ground cue at 7 m says 1.204 m
    ground = cue("ground", [ground_range], 0.2, 0.4)
    h, frame_var, spread, valid = height_measurements(cue("height", [10.0], 0.3), ground, ORIGIN, np.array([1.72]))
    assert valid[0]
    assert h[0] == pytest.approx(expected, rel=1e-6)
    assert frame_var[0] == pytest.approx(expected**2 * ((0.3 / 10.0) ** 2 + (0.2 / ground_range) ** 2), rel=1e-6)
    assert spread[0] == pytest.approx(expected * 0.4 / ground_range, rel=1e-6)


def test_an_impossible_height_is_no_measurement():
    *_, valid = height_measurements(cue("height", [10.0, 10.0], 0.3), cue("ground", [3.0, 16.0], 0.2),
                                    ORIGIN, np.array([1.72, 1.72]))
    assert not valid.any()  # 0.52 m and 2.75 m


def test_the_per_person_part_does_not_average_away_and_the_gate_drops_an_outlier():
    config = FusedConfig()
    sums = np.zeros((1, 2, 3))
    for _ in range(200):  # the frame-to-frame part averages out, the per-person 0.1 m stays
        m, s = track_heights(sums, config)
        measured = (np.array([1.30]), np.array([0.2**2]), np.array([0.1]), np.array([True]))
        sums[:, 0] = add_measurements(sums[:, 0], m, s, measured)
    m, s = track_heights(sums, config)
    prior = prior_std(config)
    expected_var = 1.0 / (1.0 / prior**2 + 1.0 / (0.2**2 / 200 + 0.1**2))
    assert s[0] == pytest.approx(prior, rel=1e-6)  # the mean moves, its spread stays the prior's
    assert 1.30 < m[0] < 1.72 and m[0] == pytest.approx(expected_var * (1.72 / prior**2 + 1.30 / (0.2**2 / 200 + 0.01)))
    far = 1.72 + 1.01 * GATE_SIGMAS * np.sqrt(prior**2 + 0.01**2)
    unchanged = add_measurements(np.zeros((1, 3)), np.array([1.72]), np.array([prior]),
                                 (np.array([far]), np.array([0.01**2]), np.array([0.0]), np.array([True])))
    assert not unchanged.any()


def test_a_child_among_adults_is_learned_and_placed_better():
    # a 1.2 m child and three adults 6-9 m ahead of a standing camera on a flat road, exact skeletons
    ground = np.array([[7.0, 1.0, 0.0], [6.0, -2.0, 0.0], [8.0, 3.0, 0.0], [9.0, -1.0, 0.0]])
    heights = [1.2, 1.72, 1.72, 1.72]
    config = Config(method="paper").replace(method="fused", fused={"ankle_keypoint_offset_m": 0.0})
    model = PedestrianEnvironmentModel(config)
    states = [model.update(make_frame(ground, heights, index=i, timestamp=0.1 * i)) for i in range(30)]
    child = lambda state: int(np.argmin(np.linalg.norm(state.pedestrians.positions[:, :2] - ground[0, :2], axis=1)))  # noqa: E731
    error = [np.linalg.norm(s.pedestrians.positions[child(s), :2] - ground[0, :2]) for s in (states[0], states[-1])]
    mean, _ = track_heights(model.locator.history.height_sums, config.fused)
    # the child's height halfway from the prior to the truth (the road under them may be off the
    # vehicle's plane by ROAD_HEIGHT_STD_M, which repeats frame after frame); the adults' stay near
    assert np.sort(mean)[0] < 1.55
    np.testing.assert_allclose(np.sort(mean)[1:], 1.72, atol=0.06)
    assert error[1] < 0.6 * error[0]  # 2.2 m on the first frame (the prior and the ground cue)
