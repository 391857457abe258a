"""Motion state with hysteresis: standing, walking or running, from the filtered speed and its spread."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.behaviour.config import BehaviourConfig

STANDING, WALKING, RUNNING = 0, 1, 2
#: Names of the motion states, indexed by code (the confusion tables of ``evaluation.behaviour``).
MOTION_STATE_NAMES = ("standing", "walking", "running")
#: A filtered speed counts as above a threshold (``behaviour.walk_enter_mps``, ``run_enter_mps``;
#: the walking direction's minimum speed) only when it exceeds it by this many of its standard
#: deviations (1.5: about 93 % one-sided), so a standing person's filter noise does not start a walk.
SPEED_SIGMAS = 1.5


@dataclass(frozen=True)
class VelocityStats:
    """Velocities (N, 2) m/s with covariances (N, 2, 2) (m/s)^2, summarised once per frame for the
    cues that use them: speed (N,) m/s and var_along (N,) (m/s)^2, the variance along the velocity;
    the rest on demand (the walking direction needs them only when the heading grids are updated)."""

    speed: np.ndarray
    var_along: np.ndarray
    velocities: np.ndarray
    covariances: np.ndarray

    def unit(self) -> np.ndarray:
        """(N, 2) the velocity's direction (zero at standstill)."""
        return self.velocities * (1.0 / np.maximum(self.speed, 1e-9))[:, None]

    def var_across(self) -> np.ndarray:
        """(N,) (m/s)^2 the variance across the velocity (0 at standstill)."""
        vx, vy = self.velocities[:, 0], self.velocities[:, 1]
        a, b, d = self.covariances[:, 0, 0], self.covariances[:, 0, 1], self.covariances[:, 1, 1]
        return (a * (vy * vy) - (2.0 * b) * (vx * vy) + d * (vx * vx)) / np.maximum(self.speed, 1e-9) ** 2

    def var_largest(self) -> np.ndarray:
        """(N,) (m/s)^2 the covariance's larger eigenvalue."""
        a, b, d = self.covariances[:, 0, 0], self.covariances[:, 0, 1], self.covariances[:, 1, 1]
        return 0.5 * (a + d) + np.sqrt(np.maximum(0.25 * (a - d) ** 2 + b**2, 0.0))


def velocity_stats(velocities: np.ndarray, velocity_covariances: np.ndarray) -> VelocityStats:
    """:class:`VelocityStats` of velocities (N, 2) m/s with covariances (N, 2, 2) (m/s)^2."""
    vx, vy = velocities[:, 0], velocities[:, 1]
    a, b, d = velocity_covariances[:, 0, 0], velocity_covariances[:, 0, 1], velocity_covariances[:, 1, 1]
    speed = np.hypot(vx, vy)
    along = (a * (vx * vx) + (2.0 * b) * (vx * vy) + d * (vy * vy)) / np.maximum(speed, 1e-9) ** 2
    return VelocityStats(speed, along, velocities, velocity_covariances)


def speed_and_std(velocities: np.ndarray, velocity_covariances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Speed (N,) m/s and its standard deviation (N,) of velocities (N, 2) m/s with covariances
    (N, 2, 2) (m/s)^2 (along the velocity; at standstill the larger axis)."""
    return speed_from(velocity_stats(velocities, velocity_covariances))


def speed_from(v: VelocityStats) -> tuple[np.ndarray, np.ndarray]:
    """:func:`speed_and_std` from the :class:`VelocityStats`."""
    moving = len(v.speed) and v.speed.min() > 1e-6
    var = v.var_along if moving else np.where(v.speed > 1e-6, v.var_along, v.var_largest())
    return v.speed, np.sqrt(np.maximum(var, 0.0))


def next_state(previous: np.ndarray, speed: np.ndarray, speed_std: np.ndarray, config: BehaviourConfig) -> np.ndarray:
    """(N,) int8 states after this frame, from the previous ones (N,) (a new track: standing), the
    speed (N,) m/s and its standard deviation (N,) (finite: the estimator's states are).

    Up a state once the speed exceeds its entry threshold by :data:`SPEED_SIGMAS` standard
    deviations; down once the speed falls below the exit threshold. Between the two the
    state holds, so it does not flicker.
    """
    # the state may fall to the number of exit thresholds the speed stays above, and rises to the
    # number of entry thresholds it clearly exceeds (the entries lie above the exits)
    low = speed - SPEED_SIGMAS * speed_std
    floor = np.add(low > config.walk_enter_mps, low > config.run_enter_mps, dtype=np.int8)  # entries < low
    ceiling = np.add(speed >= config.walk_exit_mps, speed >= config.run_exit_mps, dtype=np.int8)  # exits <= speed
    return np.maximum(np.minimum(previous, ceiling), floor).astype(np.int8, copy=False)
