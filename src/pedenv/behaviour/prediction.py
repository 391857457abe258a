"""The predicted path: positions ahead with covariances, from each track's constant-velocity filter."""

from __future__ import annotations

import numpy as np

_EYE2 = np.eye(2)


def predict_path(x: np.ndarray, P: np.ndarray, horizons: np.ndarray, acceleration_std: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Positions (N, H, 2) world x-y, metres, and covariances (N, H, 2, 2) m^2 at ``horizons``
    (H,) seconds ahead of the filter states x (N, 4) ``[x, vx, y, vy]`` with covariances P
    (N, 4, 4): the constant-velocity model of :mod:`pedenv.kalman` (``kalman.transition``)
    in closed form, all horizons at once. Its process noise adds ``a^2 t^4 / 4`` per axis.
    """
    t = np.asarray(horizons, float)[None, :]
    pos, vel = x[:, [0, 2]], x[:, [1, 3]]
    positions = pos[:, None, :] + t[..., None] * vel[:, None, :]
    pp = P[:, [0, 2]][:, :, [0, 2]]
    pv = P[:, [0, 2]][:, :, [1, 3]]
    vv = P[:, [1, 3]][:, :, [1, 3]]
    tt = t[..., None, None]
    cov = (pp[:, None] + tt * (pv + np.transpose(pv, (0, 2, 1)))[:, None] + tt**2 * vv[:, None]
           + (acceleration_std**2 * tt**4 / 4.0) * _EYE2)
    return positions, cov
