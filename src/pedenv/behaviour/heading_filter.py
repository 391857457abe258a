"""A filter on the circle for each track's body heading: a grid (histogram) filter, batched.

Each track holds a probability over B equal cells of the heading (world yaw, radians, cell
``k`` centred on ``-pi + (k + 0.5) 2 pi / B``). Predicting over ``dt`` seconds convolves it
with a wrapped normal of variance ``q^2 dt`` (a random walk of the heading, done per row in
the Fourier domain, so every track may have its own ``dt``); a cue multiplies it by its
likelihood. A grid holds what a single von Mises cannot: the two mirror images the shoulders
alone leave open, and the front-or-back ambiguity of a profile.

The summary follows Autoware's ``orientation_availability``: ``AVAILABLE`` when the
probability gathers about its mode (spread below a threshold), ``SIGN_UNKNOWN`` when it
gathers only about the mode's axis (mode or mode + 180 degrees), else ``UNAVAILABLE``.
"""

from __future__ import annotations

import numpy as np

UNAVAILABLE, SIGN_UNKNOWN, AVAILABLE = 0, 1, 2
#: Names of the availability codes, indexed by code.
AVAILABILITY_NAMES = ("unavailable", "sign_unknown", "available")


def cell_centres(bins: int) -> np.ndarray:
    """(B,) the cells' centre angles, radians in [-pi, pi)."""
    return -np.pi + (np.arange(bins) + 0.5) * (2.0 * np.pi / bins)


def uniform(n: int, bins: int) -> np.ndarray:
    """(n, B) the flat distribution (nothing known)."""
    return np.full((n, bins), 1.0 / bins)


def predict(p: np.ndarray, dt: np.ndarray, random_walk_rad: float) -> np.ndarray:
    """Spread distributions p (N, B) over dt (N,) seconds (heading random walk, rad / sqrt(s))."""
    if not len(p):
        return p
    var = random_walk_rad**2 * np.clip(np.where(np.isnan(dt), 1e3, dt), 0.0, 1e3)
    k = np.arange(p.shape[1] // 2 + 1)
    damp = np.exp(-0.5 * np.minimum(var, 1e3)[:, None] * k[None, :] ** 2)
    out = np.fft.irfft(np.fft.rfft(p, axis=1) * damp, n=p.shape[1], axis=1)
    return normalise(np.maximum(out, 0.0))


def update(p: np.ndarray, likelihood: np.ndarray) -> np.ndarray:
    """Bayes' rule on the grid: p (N, B) times likelihood (N, B), normalised (flat if it vanished)."""
    return normalise(p * likelihood)


def normalise(p: np.ndarray) -> np.ndarray:
    total = p.sum(axis=1, keepdims=True)
    flat = ~(total > 1e-300) | ~np.isfinite(total)
    return np.where(flat, 1.0 / p.shape[1], p / np.where(flat, 1.0, total))


def summary(p: np.ndarray, available_std_rad: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``yaw`` (N,) radians, world, the mode refined by the mean of its neighbourhood (+-3 cells);
    ``std`` (N,) radians, the spread about it (at most that of a flat distribution, 1.81);
    ``availability`` (N,) int8 (see the module docstring)."""
    n, bins = p.shape
    if n == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0, np.int8)
    cells = cell_centres(bins)
    best = p.argmax(axis=1)
    near = (best[:, None] + np.arange(-3, 4)[None, :]) % bins
    w = p[np.arange(n)[:, None], near]
    yaw = np.arctan2((w * np.sin(cells[near])).sum(1), (w * np.cos(cells[near])).sum(1))
    diff = _wrap(cells[None, :] - yaw[:, None])
    std = np.sqrt((p * diff**2).sum(axis=1))
    axial = np.sqrt((p * _wrap_half(diff) ** 2).sum(axis=1))
    availability = np.where(std < available_std_rad, AVAILABLE,
                            np.where(axial < available_std_rad, SIGN_UNKNOWN, UNAVAILABLE)).astype(np.int8)
    return _wrap(yaw), std, availability


def probability_within(p: np.ndarray, centre: np.ndarray, half_angle: float) -> np.ndarray:
    """(N,) the probability that the heading lies within ``half_angle`` radians of centre (N,)."""
    cells = cell_centres(p.shape[1])
    inside = np.abs(_wrap(cells[None, :] - centre[:, None])) <= half_angle
    return np.clip((p * inside).sum(axis=1), 0.0, 1.0)


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def _wrap_half(a: np.ndarray) -> np.ndarray:
    return (a + 0.5 * np.pi) % np.pi - 0.5 * np.pi
