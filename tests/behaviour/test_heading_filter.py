"""The grid filter on the circle: prediction spreads, summary and availability."""

import numpy as np
import pytest

from pedenv.behaviour import heading_filter as hf

CELLS = hf.cell_centres(72)


def _peaked(centres, kappa=40.0):
    p = sum(np.exp(kappa * (np.cos(CELLS - c) - 1.0)) for c in centres)
    return hf.normalise(np.atleast_2d(p))


@pytest.mark.parametrize("centres, expected", [
    ([0.7], hf.AVAILABLE), ([0.7, 0.7 + np.pi], hf.SIGN_UNKNOWN), ([0.0, 2.1, 4.2], hf.UNAVAILABLE),
])
def test_availability_follows_autoware(centres, expected):
    yaw, std, available = hf.summary(_peaked(centres), np.radians(40))
    assert available[0] == expected
    assert min(abs(hf._wrap(yaw[0] - c)) for c in centres) < np.radians(3)


def test_prediction_spreads_with_time_and_a_gap_of_seconds_forgets():
    p = _peaked([1.0])
    stds = [hf.summary(hf.predict(p, np.array([dt]), np.radians(45)), np.radians(40))[1][0] for dt in (0.1, 1.0, 5.0)]
    assert stds[0] < stds[1] < stds[2]
    _, std, available = hf.summary(hf.predict(p, np.array([5.0]), np.radians(45)), np.radians(40))
    assert available[0] == hf.UNAVAILABLE and 1.4 < std[0] <= np.pi / np.sqrt(3) + 0.01


def test_update_with_a_vanishing_likelihood_is_flat_not_nan():
    p = hf.update(_peaked([0.0]), np.zeros((1, 72)))
    assert np.isfinite(p).all() and np.ptp(p) == 0


def test_body_facing_counts_the_cells_near_the_direction_to_the_camera():
    from pedenv.behaviour.facing import body_facing_from

    p, cells = _peaked([0.0], kappa=400.0), hf.cell_centres(72)
    assert body_facing_from(p, np.cos(cells)[None], np.cos(np.radians(30)))[0] > 0.99
    assert body_facing_from(p, np.cos(cells - np.pi)[None], np.cos(np.radians(30)))[0] < 0.01


def test_a_shared_time_step_takes_the_kernel_and_agrees_with_the_fourier_path():
    p = np.vstack([_peaked([0.3]), _peaked([2.0, 2.0 + np.pi]), hf.uniform(1, 72)])
    g = hf.grid(72)
    shared = hf.spread(p, np.full(3, 0.1), np.radians(45), g)  # one dt: the circulant kernel
    mixed = hf.spread(np.vstack([p, p[:1]]), np.array([0.1, 0.1, 0.1, 0.2]), np.radians(45), g)  # the FFT
    assert np.abs(shared - mixed[:3]).max() < 1e-15 and np.allclose(shared.sum(axis=1), 1.0)


@pytest.mark.parametrize("first, second", [(0.3, 0.3), (0.1, 0.6), (0.0, 2.0)])
def test_spreading_over_two_gaps_in_turn_is_spreading_over_their_sum(first, second):
    # the estimator predicts every grid at each orientation update (so that all share one time step)
    # instead of a returning track over its whole gap at once: the same, a wrapped normal's variances add
    p = np.vstack([_peaked([1.0]), _peaked([0.5, 0.5 + np.pi], kappa=5.0)])
    walk, g = np.radians(45), hf.grid(72)
    in_turn = hf.spread(hf.spread(p, np.array([first, first]), walk, g), np.array([second, second]), walk, g)
    at_once = hf.spread(p, np.array([first + second, 0.0]), walk, g)[:1]  # mixed steps: the Fourier path
    assert np.abs(in_turn[:1] - at_once).max() < 1e-15
    assert np.abs(in_turn - hf.spread(p, np.full(2, first + second), walk, g)).max() < 1e-15
