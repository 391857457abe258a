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


class Grid:
    """The constant tables of a B-cell grid, computed once (the estimator holds one).

    cells (B,) radians; cos_sin (2, B) their cosines and sines; freq_sq (M,) the squared
    frequencies of the real Fourier transform (M = B // 2 + 1); the mode's neighbourhood
    (+-3 cells) and its offsets' cosines and sines (7, 2) for :func:`summary`.
    """

    def __init__(self, bins: int) -> None:
        self.bins = bins
        self.cells = cell_centres(bins)
        self.cos_sin = np.stack([np.cos(self.cells), np.sin(self.cells)])
        self.freq_sq = np.arange(bins // 2 + 1).astype(float) ** 2
        self.neighbours = np.arange(-3, 4)
        step = self.neighbours * (2.0 * np.pi / bins)
        self.neighbour_cos_sin = np.column_stack([np.cos(step), np.sin(step)])
        self._kernels: dict[float, np.ndarray] = {}

    def kernel(self, var: float) -> np.ndarray:
        """(B, B) the circulant matrix that convolves a row p (B,) with a wrapped normal of variance
        ``var`` rad^2 (``p @ kernel``), kept per variance (a frame's tracks share one)."""
        matrix = self._kernels.get(var)
        if matrix is None:
            row = np.fft.irfft(np.exp(-0.5 * min(var, 1e3) * self.freq_sq), n=self.bins)  # the kernel, by cell offset
            matrix = row[(np.arange(self.bins)[None, :] - np.arange(self.bins)[:, None]) % self.bins]
            if len(self._kernels) >= MAX_KERNELS:
                self._kernels.clear()
            self._kernels[var] = matrix
        return matrix


#: Kernels a :class:`Grid` keeps (one per distinct prediction variance; a frame rate's few).
MAX_KERNELS = 64


_GRIDS: dict[int, Grid] = {}


def grid(bins: int) -> Grid:
    """The (cached) :class:`Grid` of ``bins`` cells."""
    if bins not in _GRIDS:
        _GRIDS[bins] = Grid(bins)
    return _GRIDS[bins]


def uniform(n: int, bins: int) -> np.ndarray:
    """(n, B) the flat distribution (nothing known)."""
    return np.full((n, bins), 1.0 / bins)


def spread(p: np.ndarray, dt: np.ndarray, random_walk_rad: float, g: Grid) -> np.ndarray:
    """p (N, B) convolved with a wrapped normal of variance ``q^2 dt`` per row (dt (N,) seconds,
    finite), not normalised (its rows keep their sums, up to the clipped rounding). Rows sharing
    one ``dt`` (the usual frame) take one matrix product with :meth:`Grid.kernel`, others the FFT."""
    dt = np.minimum(np.maximum(dt, 0.0), 1e3)
    if len(dt) and (dt == dt[0]).all():
        return np.maximum(p @ g.kernel(random_walk_rad**2 * float(dt[0])), 0.0)
    var = random_walk_rad**2 * dt
    damp = np.exp(np.multiply.outer(-0.5 * np.minimum(var, 1e3), g.freq_sq))
    return np.maximum(np.fft.irfft(np.fft.rfft(p, axis=1) * damp, n=g.bins, axis=1), 0.0)


def predict(p: np.ndarray, dt: np.ndarray, random_walk_rad: float) -> np.ndarray:
    """Spread distributions p (N, B) over dt (N,) seconds (heading random walk, rad / sqrt(s))."""
    if not len(p):
        return p
    dt = np.where(np.isnan(dt), 1e3, dt)
    return normalise(spread(p, dt, random_walk_rad, grid(p.shape[1])))


def update(p: np.ndarray, likelihood: np.ndarray) -> np.ndarray:
    """Bayes' rule on the grid: p (N, B) times likelihood (N, B), normalised (flat if it vanished)."""
    return normalise(p * likelihood)


def normalise(p: np.ndarray) -> np.ndarray:
    total = p.sum(axis=1, keepdims=True)
    if len(total) and total.min() > 1e-300 and total.max() < np.inf:  # the usual case (False for NaN)
        return p / total
    flat = ~(total > 1e-300) | ~np.isfinite(total)
    return np.where(flat, 1.0 / p.shape[1], p / np.where(flat, 1.0, total))


def summary(p: np.ndarray, available_std_rad: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``yaw`` (N,) radians, world, the mode refined by the mean of its neighbourhood (+-3 cells);
    ``std`` (N,) radians, the spread about it (at most that of a flat distribution, 1.81);
    ``availability`` (N,) int8 (see the module docstring)."""
    n, bins = p.shape
    if n == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0, np.int8)
    g = grid(bins)
    best = p.argmax(axis=1)
    near = p.take(((best[:, None] + g.neighbours) % bins) + bins * np.arange(n)[:, None])  # (N, 7)
    local = near @ g.neighbour_cos_sin  # (N, 2): the neighbourhood's mean direction, from the mode's cell
    yaw = _wrap(g.cells[best] + np.arctan2(local[:, 1], local[:, 0]))
    diff = g.cells - yaw[:, None]  # in (-2 pi, 2 pi): wrapped to [-pi, pi] below
    diff -= (2.0 * np.pi) * np.rint(diff * (0.5 / np.pi))
    sq = diff * diff
    std = np.sqrt((p * sq).sum(axis=1))
    np.abs(diff, out=diff)
    diff -= np.pi
    axial = np.sqrt((p * np.minimum(sq, diff * diff)).sum(axis=1))  # about the axis: the nearer end
    # axial <= std (each term no larger, summed in the same order): AVAILABLE counts both
    availability = (std < available_std_rad).view(np.int8) + (axial < available_std_rad).view(np.int8)
    return yaw, std, availability


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2.0 * np.pi) - np.pi
