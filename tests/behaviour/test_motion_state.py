"""Motion state: the speed posterior under the population prior, and hysteresis between standing, walking
and running."""

import numpy as np
import pytest

from pedenv.behaviour import motion_state
from pedenv.behaviour.config import BehaviourConfig
from pedenv.behaviour.motion_state import (
    RUNNING,
    STANDING,
    WALKING,
    next_state,
    speed_and_std,
    speed_posterior,
)
from pedenv.kalman import INITIAL_VELOCITY_STD_MPS

CFG = BehaviourConfig(enabled=True)


def _cov(*stds: float) -> np.ndarray:
    return np.array([np.diag([s * s, s * s]) for s in stds])


def test_hysteresis_does_not_flicker():
    speeds = [0.0, 0.4, 0.9, 0.5, 0.4, 0.25, 0.5, 3.5, 2.5, 2.0]
    state, out = np.array([STANDING], np.int8), []
    for v in speeds:
        state = next_state(state, np.array([v]), CFG)
        out.append(int(state[0]))
    # 0.4 m/s does not start a walk (entry 0.45) and does not end one (exit 0.3); a sprint from standing
    # goes straight to running; 2.5 m/s still runs (exit 2.3), 2.0 walks
    assert out == [STANDING, STANDING, WALKING, WALKING, WALKING, STANDING, WALKING, RUNNING, RUNNING, WALKING]


def test_a_well_measured_speed_is_its_own():
    velocities = np.array([[1.4, 0.0], [0.0, 0.05], [0.0, 3.0]])
    median, mean, _ = speed_posterior(velocities, _cov(0.05, 0.05, 0.05))
    assert median == pytest.approx([1.4, 0.0, 3.0], abs=0.1)
    assert mean == pytest.approx(velocities, abs=0.05)
    assert next_state(np.zeros(3, np.int8), median, CFG).tolist() == [WALKING, STANDING, RUNNING]


def test_a_track_with_no_information_yet_gets_the_population_prior():
    # the filter's state of a new track (its own prior: zero velocity, INITIAL_VELOCITY_STD_MPS per axis),
    # and one the process noise widened beyond it: the prior's median, 1.1 m/s (30 % stand, 65 % walk at
    # 1.35 +- 0.4 m/s), calls them walking; the mean velocity is zero (no direction known)
    median, mean, _ = speed_posterior(np.zeros((2, 2)), _cov(INITIAL_VELOCITY_STD_MPS, 3.0))
    assert median == pytest.approx([1.1, 1.1])
    assert np.abs(mean).max() < 1e-9
    assert next_state(np.zeros(2, np.int8), median, CFG).tolist() == [WALKING, WALKING]


def test_an_uncertain_speed_is_drawn_toward_a_walkers():
    # 3 m/s +- 1 m/s (a far track whose range jumps; running if it were exact): the posterior walks, at
    # 1.8 m/s (measured); the mean velocity keeps the direction, at about that speed
    median, mean, _ = speed_posterior(np.array([[0.0, -3.0]]), _cov(1.0))
    assert 1.3 < median[0] < 2.3
    assert mean[0, 0] == pytest.approx(0.0, abs=1e-9) and -2.3 < mean[0, 1] < -1.3
    # a standing person's filter noise (0.35 m/s +- 0.25) stays standing, a young walker's 1.2 +- 0.8 walks
    median, _, _ = speed_posterior(np.array([[0.35, 0.0], [0.0, 1.2]]), _cov(0.25, 0.8))
    assert next_state(np.zeros(2, np.int8), median, CFG).tolist() == [STANDING, WALKING]


def test_an_empty_frame_and_a_degenerate_covariance():
    median, mean, _ = speed_posterior(np.zeros((0, 2)), np.zeros((0, 2, 2)))
    assert median.shape == (0,) and mean.shape == (0, 2)
    # an exact velocity (zero covariance, or a singular one) is taken as measured
    cov = np.array([np.zeros((2, 2)), [[1e-4, 1e-4], [1e-4, 1e-4]]])
    median, mean, _ = speed_posterior(np.array([[1.0, 0.0], [0.0, 1.3]]), cov)
    assert median == pytest.approx([1.0, 1.3]) and mean == pytest.approx(np.array([[1.0, 0.0], [0.0, 1.3]]), abs=0.01)


def test_speed_and_std_at_standstill_uses_the_widest_axis():
    speed, std = speed_and_std(np.zeros((1, 2)), np.array([[[0.04, 0.0], [0.0, 0.09]]]))
    assert speed[0] == 0 and np.isclose(std[0], 0.3)


def test_one_far_off_velocity_does_not_decide(monkeypatch):
    # 4 m/s +- 0.5 (a range that jumps: the KITTI drives' filter velocities are now and then far off their
    # spread): the heavy-tailed likelihood lets the population prior call it a walker (1.6 m/s measured);
    # with a Gaussian likelihood alone it would run at 3.9 m/s. A runner measured to 0.15 m/s still runs.
    velocities, cov = np.array([[4.0, 0.0], [3.5, 0.0]]), _cov(0.5, 0.15)
    median, mean, corridor = speed_posterior(velocities, cov)
    assert next_state(np.zeros(2, np.int8), median, CFG).tolist() == [WALKING, RUNNING]
    assert 1.3 < median[0] < 2.0 and 1.3 < mean[0, 0] < 2.0 and median[1] == pytest.approx(3.5)
    assert corridor[0, 0] > 3.5 and abs(corridor[0, 1]) < 1e-9  # the Gaussian alone (the corridor's): 3.8 m/s
    monkeypatch.setattr(motion_state, "OUTLIER_SHARE", 1e-12)
    gaussian, _, _ = speed_posterior(velocities, cov)
    assert gaussian[0] == pytest.approx(3.9) and next_state(np.zeros(1, np.int8), gaussian[:1], CFG)[0] == RUNNING
