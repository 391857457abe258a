"""The predicted path of a walker at constant speed, through the track's Kalman filter."""

import numpy as np
import pytest

from pedenv import kalman
from pedenv.behaviour.prediction import PathPredictor, predict_path

HORIZONS = np.array([0.5, 1.0, 2.0, 3.0])


def _walk(seed: int, noise_m: float, seconds: float = 4.0, acceleration_std: float = 1.0):
    """The filter state after ``seconds`` of a walker at 1.4 m/s along x measured at 10 Hz with
    ``noise_m`` per axis, and its true position then."""
    rng = np.random.default_rng(seed)
    F, Q = kalman.transition(0.1, acceleration_std)
    r = np.eye(2)[None] * noise_m**2
    truth = lambda t: np.array([1.4 * t, 5.0])  # noqa: E731
    x, P = kalman.initial_state((truth(0.0) + rng.normal(0, noise_m, 2))[None], r, 2.0)
    for k in range(1, int(round(seconds / 0.1)) + 1):
        x, P = kalman.predict(x, P, F, Q)
        x, P = kalman.update(x, P, (truth(0.1 * k) + rng.normal(0, noise_m, 2))[None], r)
    return x, P, truth(seconds)


def test_a_walker_at_constant_speed_is_predicted_along_its_line():
    x, P, now = _walk(0, 0.0)
    positions, cov = predict_path(x, P, HORIZONS, 1.0)
    assert np.allclose(positions[0], now + HORIZONS[:, None] * [1.4, 0.0], atol=1e-6)
    assert (np.diff(cov[0, :, 0, 0]) > 0).all()  # the spread grows with the horizon


def test_the_error_at_2_s_matches_the_filters_noise_and_its_covariance():
    # 200 walkers, 0.2 m white noise per axis (about pedenv's frame-to-frame spread within 15 m),
    # 4 s of track: mean FDE at 2 s 0.40 m (0.21 m with a 0.3 m/s^2 filter; on the synthetic scenes,
    # whose noise is not white, a slower filter does not help: docs/behaviour.md). The covariance,
    # dominated by the 1 m/s^2 process noise (2 m per axis at 2 s), is conservative: mean squared
    # error over its trace 0.024
    predictor, errors, spreads = PathPredictor(HORIZONS, 1.0), [], []
    for seed in range(200):
        x, P, now = _walk(seed, 0.2)
        positions, cov = predictor(x, P)
        errors.append(np.linalg.norm(positions[0, 2] - (now + [2.8, 0.0])))
        spreads.append(np.trace(cov[0, 2]))
    errors, spreads = np.array(errors), np.array(spreads)
    assert errors.mean() == pytest.approx(0.40, abs=0.02)
    assert (errors**2).mean() / spreads.mean() == pytest.approx(0.024, abs=0.003)
