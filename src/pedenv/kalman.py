"""Constant-velocity Kalman filter on the ground plane, batched over tracks.

State per track ``[x, vx, y, vy]`` (world frame, metres and metres per second). The
process noise is the discrete white-noise acceleration model (Bar-Shalom, *Estimation
with Applications to Tracking and Navigation*, Sec. 6.3.3), in the order of filterpy's
``Q_discrete_white_noise(dim=2, block_size=2, order_by_dim=True)``; the batched
predict/update is plain numpy so that a frame with a hundred pedestrians costs a few
array operations. ``tests/test_kalman.py`` checks both against filterpy's own filter.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pedenv.geometry import inverse_2x2

if TYPE_CHECKING:
    from pedenv.config_tracking import KalmanConfig

#: Measurement matrix: the filter observes x and y.
H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
#: Smallest variance (m^2, a 1 mm std) a measurement may claim in any direction. A
#: measurement exact along one direction, met by a state that is exact along the same
#: direction, would make the innovation covariance singular and the gain explode.
MIN_MEASUREMENT_VARIANCE = 1e-6
#: Prior spread (m/s, per axis) of a new track's velocity: a walker's speed (1.4 m/s) with
#: room for a runner's; the filter's first updates replace it. Tuned on the built-in scenes
#: with the other filter settings; no measurement told other values apart.
INITIAL_VELOCITY_STD_MPS = 2.0


def transition(dt: float, acceleration_std: float) -> tuple[np.ndarray, np.ndarray]:
    """``(F, Q)`` (4, 4) of the constant-velocity model over ``dt`` seconds.

    Q is the discrete white-noise acceleration with variance ``acceleration_std**2``: per
    axis ``var * [[dt^4/4, dt^3/2], [dt^3/2, dt^2]]``.
    """
    f1 = np.array([[1.0, dt], [0.0, 1.0]])
    q1 = acceleration_std**2 * np.array([[dt**4 / 4.0, dt**3 / 2.0], [dt**3 / 2.0, dt**2]])
    F, Q = np.zeros((4, 4)), np.zeros((4, 4))
    F[:2, :2] = F[2:, 2:] = f1
    Q[:2, :2] = Q[2:, 2:] = q1
    return F, Q


def initial_state(z: np.ndarray, r: np.ndarray, velocity_std: float) -> tuple[np.ndarray, np.ndarray]:
    """New tracks at measurements z (N, 2) with covariance r (N, 2, 2), standing still."""
    n = len(z)
    x = np.zeros((n, 4))
    x[:, 0], x[:, 2] = z[:, 0], z[:, 1]
    P = np.zeros((n, 4, 4))
    P[:, 0, 0], P[:, 0, 2], P[:, 2, 0], P[:, 2, 2] = r[:, 0, 0], r[:, 0, 1], r[:, 1, 0], r[:, 1, 1]
    P[:, 1, 1] = P[:, 3, 3] = velocity_std**2
    return x, P


def predict(x: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Propagate states x (N, 4) and covariances P (N, 4, 4) one step."""
    return x @ F.T, F @ P @ F.T + Q


def update(x: np.ndarray, P: np.ndarray, z: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fuse measurements z (N, 2) with covariance r: (N,) per-axis variances or (N, 2, 2).

    Joseph form, so P stays symmetric positive semi-definite.
    """
    R = floor_variance(r[:, None, None] * np.eye(2) if r.ndim == 1 else r)
    S = H @ P @ H.T + R
    PHt = P @ H.T
    K = PHt @ inverse_2x2(S)
    innovation = z - x @ H.T
    x = x + np.einsum("nij,nj->ni", K, innovation)
    I_KH = np.eye(4) - K @ H
    P = I_KH @ P @ np.transpose(I_KH, (0, 2, 1)) + K @ R @ np.transpose(K, (0, 2, 1))
    return x, P


def floor_variance(R: np.ndarray) -> np.ndarray:
    """Covariances (N, 2, 2) whose smaller eigenvalue lies below :data:`MIN_MEASUREMENT_VARIANCE`
    raised to it (by adding the shortfall times the identity); the others as they are."""
    a, b, d = R[:, 0, 0], 0.5 * (R[:, 0, 1] + R[:, 1, 0]), R[:, 1, 1]
    smallest = 0.5 * (a + d) - np.sqrt(np.maximum(0.25 * (a - d) ** 2 + b**2, 0.0))
    short = smallest < MIN_MEASUREMENT_VARIANCE
    if not short.any():
        return R
    R = R.copy()
    R[short] += (MIN_MEASUREMENT_VARIANCE - smallest[short])[:, None, None] * np.eye(2)
    return R


def innovation_distance(x: np.ndarray, P: np.ndarray, z: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Squared Mahalanobis distance (N,) of measurements z (N, 2), covariance r (N, 2, 2),
    from the predicted states x (N, 4), P (N, 4, 4)."""
    S = H @ P @ H.T + r
    e = z - x @ H.T
    return np.einsum("ni,nij,nj->n", e, inverse_2x2(S), e)


def correct(x: np.ndarray, P: np.ndarray, started: np.ndarray, z: np.ndarray, r: np.ndarray, spread: np.ndarray,
            config: KalmanConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One frame's correction of the tracks that have a measurement.

    x (N, 4), P (N, 4, 4): predicted states; started (N,) bool: the filter holds a state.
    z (N, 2): measured ground points, world x-y, metres, with frame-to-frame covariance
    r (N, 2, 2) and whole spread (``r`` plus the per-person bias) ``spread`` (N, 2, 2).
    A track not started, or (with ``config.restart_gate`` > 0, a ``KalmanConfig``) one whose
    measurement lies beyond the gate, starts again at its measurement.
    A row whose measurement (z, r or spread) holds NaN or inf is no measurement: its state
    is left as it is, so no non-finite value enters a track's state.
    Returns the corrected ``(x, P)`` and ``measured`` (N,) bool, the rows corrected.
    """
    x, P = x.copy(), P.copy()
    measured = (np.isfinite(z).all(axis=1) & np.isfinite(r).reshape(len(r), -1).all(axis=1)
                & np.isfinite(spread).reshape(len(spread), -1).all(axis=1))
    fresh = ~started & measured
    known = started & measured
    if config.restart_gate > 0 and known.any():
        far = np.zeros(len(x), bool)
        far[known] = innovation_distance(x[known], P[known], z[known], spread[known]) > config.restart_gate
        fresh |= far
    if fresh.any():
        x[fresh], P[fresh] = initial_state(z[fresh], r[fresh], INITIAL_VELOCITY_STD_MPS)
    step = measured & ~fresh
    if step.any():
        x[step], P[step] = update(x[step], P[step], z[step], r[step])
    return x, P, measured


def finite_states(x: np.ndarray, P: np.ndarray) -> np.ndarray:
    """(N,) bool: states x (N, 4) and covariances P (N, 4, 4) free of NaN and inf."""
    return np.isfinite(x).all(axis=1) & np.isfinite(P).reshape(len(P), -1).all(axis=1)
