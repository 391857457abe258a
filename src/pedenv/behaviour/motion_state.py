"""Motion state with hysteresis: standing, walking or running, from the filtered speed and its spread."""

from __future__ import annotations

import numpy as np

from pedenv.behaviour.config import BehaviourConfig

STANDING, WALKING, RUNNING = 0, 1, 2
#: Names of the motion states, indexed by code.
MOTION_STATE_NAMES = ("standing", "walking", "running")


def speed_and_std(velocities: np.ndarray, velocity_covariances: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Speed (N,) m/s and its standard deviation (N,) of velocities (N, 2) m/s with covariances
    (N, 2, 2) (m/s)^2 (along the velocity; at standstill the larger axis)."""
    speed = np.linalg.norm(velocities, axis=1)
    unit = velocities / np.maximum(speed, 1e-9)[:, None]
    along = np.einsum("ni,nij,nj->n", unit, velocity_covariances, unit)
    a, b, d = velocity_covariances[:, 0, 0], velocity_covariances[:, 0, 1], velocity_covariances[:, 1, 1]
    largest = 0.5 * (a + d) + np.sqrt(np.maximum(0.25 * (a - d) ** 2 + b**2, 0.0))
    var = np.where(speed > 1e-6, along, largest)
    return speed, np.sqrt(np.maximum(var, 0.0))


def next_state(previous: np.ndarray, speed: np.ndarray, speed_std: np.ndarray, config: BehaviourConfig) -> np.ndarray:
    """(N,) int8 states after this frame, from the previous ones (N,) (a new track: standing).

    Up a state once the speed exceeds its entry threshold by ``speed_sigmas`` standard
    deviations; down once the speed falls below the exit threshold. Between the two the
    state holds, so it does not flicker.
    """
    low = speed - config.speed_sigmas * speed_std
    state = np.asarray(previous, np.int8).copy()
    state[(state == RUNNING) & (speed < config.run_exit_mps)] = WALKING
    state[(state == WALKING) & (speed < config.walk_exit_mps)] = STANDING
    state[(state == STANDING) & (low > config.walk_enter_mps)] = WALKING
    state[(state == WALKING) & (low > config.run_enter_mps)] = RUNNING
    return state
