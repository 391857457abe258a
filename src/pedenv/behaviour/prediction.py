"""The predicted path: positions ahead with covariances, from each track's constant-velocity filter
(the estimator moves the reported path and the conflict corridor's steps at the motion state's
posterior mean velocity,
:func:`pedenv.behaviour.motion_state.speed_posterior`)."""

from __future__ import annotations

import numpy as np

_POS, _VEL = (0, 2), (1, 3)  # the state's position and velocity components, x then y


class PathPredictor:
    """The constant-velocity model of :mod:`pedenv.kalman` (``kalman.transition``) in closed form
    at ``horizons`` (H,) seconds, with the process noise of ``acceleration_std`` (m/s^2): both as
    fixed matrices, so a frame's prediction is two matrix products.

    Position ``p + t v``; covariance ``Ppp + t (Ppv + Pvp) + t^2 Pvv + a^2 t^4 / 4`` per axis.
    """

    def __init__(self, horizons: np.ndarray, acceleration_std: float) -> None:
        t = np.asarray(horizons, float)
        h = len(t)
        self.horizons = t
        self.position_map = np.zeros((4, h, 2))  # state -> (H, 2) positions
        self.covariance_map = np.zeros((16, h, 2, 2))  # flattened P -> (H, 2, 2) covariances
        self.noise = np.zeros((h, 2, 2))
        for i in range(2):
            self.position_map[_POS[i], :, i] = 1.0
            self.position_map[_VEL[i], :, i] = t
            self.noise[:, i, i] = acceleration_std**2 * t**4 / 4.0
            for j in range(2):
                self.covariance_map[4 * _POS[i] + _POS[j], :, i, j] += 1.0
                self.covariance_map[4 * _POS[i] + _VEL[j], :, i, j] += t
                self.covariance_map[4 * _VEL[i] + _POS[j], :, i, j] += t
                self.covariance_map[4 * _VEL[i] + _VEL[j], :, i, j] += t * t
        # the same by component (:meth:`stacked`): x, y; xx, xy, yy
        self.component_maps = (np.ascontiguousarray(self.position_map.transpose(0, 2, 1).reshape(4, 2 * h)),
                               np.ascontiguousarray(self.covariance_map[:, :, [0, 0, 1], [0, 1, 1]]
                                                    .transpose(0, 2, 1).reshape(16, 3 * h)),
                               np.ascontiguousarray(self.noise[:, [0, 0, 1], [0, 1, 1]].T.reshape(3 * h)))
        self.position_map = self.position_map.reshape(4, 2 * h)
        self.covariance_map = self.covariance_map.reshape(16, 4 * h)
        self.noise = self.noise.reshape(4 * h)

    def __call__(self, x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Positions (N, H, 2) world x-y, metres, and covariances (N, H, 2, 2) m^2 of the filter
        states x (N, 4) ``[x, vx, y, vy]`` with covariances P (N, 4, 4)."""
        n, h = len(x), len(self.horizons)
        positions = (x @ self.position_map).reshape(n, h, 2)
        cov = (P.reshape(n, 16) @ self.covariance_map + self.noise).reshape(n, h, 2, 2)
        return positions, cov

    def stacked(self, x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The same as :meth:`__call__`, the components stacked: positions (N, 2, H) world x, y
        metres and covariances (N, 3, H) m^2, the components xx, xy, yy."""
        n, h = len(x), len(self.horizons)
        positions = (x @ self.component_maps[0]).reshape(n, 2, h)
        cov = (P.reshape(n, 16) @ self.component_maps[1] + self.component_maps[2]).reshape(n, 3, h)
        return positions, cov


class JointPredictor:
    """Two :class:`PathPredictor` at once (the reported path's horizons H and the corridor's steps K),
    their maps side by side, so that a frame's predictions are still two matrix products."""

    def __init__(self, reported: PathPredictor, stacked: PathPredictor) -> None:
        self.sizes = (len(reported.horizons), len(stacked.horizons))
        self.position_map = np.concatenate([reported.position_map, stacked.component_maps[0]], axis=1)
        self.covariance_map = np.concatenate([reported.covariance_map, stacked.component_maps[1]], axis=1)
        self.noise = np.concatenate([reported.noise, stacked.component_maps[2]])
        self.step_map = stacked.component_maps[0]

    def reported(self, x: np.ndarray) -> np.ndarray:
        """The reported path's positions (N, H, 2) alone (:meth:`PathPredictor.__call__`), of the states x (N, 4)."""
        h = self.sizes[0]
        return (x @ self.position_map[:, :2 * h]).reshape(len(x), h, 2)

    def steps(self, x: np.ndarray) -> np.ndarray:
        """The corridor's positions (N, 2, K) alone (:meth:`PathPredictor.stacked`), of the states x (N, 4)."""
        return (x @ self.step_map).reshape(len(x), 2, self.sizes[1])

    def __call__(self, x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, ...]:
        """The reported path's positions (N, H, 2) and covariances (N, H, 2, 2) (:meth:`PathPredictor.__call__`)
        and the corridor's positions (N, 2, K) and covariances (N, 3, K) (:meth:`PathPredictor.stacked`)."""
        n, (h, k) = len(x), self.sizes
        positions = x @ self.position_map
        cov = P.reshape(n, 16) @ self.covariance_map + self.noise
        return (positions[:, :2 * h].reshape(n, h, 2), cov[:, :4 * h].reshape(n, h, 2, 2),
                positions[:, 2 * h:].reshape(n, 2, k), cov[:, 4 * h:].reshape(n, 3, k))


def predict_path(x: np.ndarray, P: np.ndarray, horizons: np.ndarray, acceleration_std: float
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Positions (N, H, 2) world x-y, metres, and covariances (N, H, 2, 2) m^2 at ``horizons``
    (H,) seconds ahead of the filter states x (N, 4) ``[x, vx, y, vy]`` with covariances P
    (N, 4, 4): the constant-velocity model of :mod:`pedenv.kalman` (``kalman.transition``)
    in closed form, all horizons at once (:class:`PathPredictor`). Its process noise adds
    ``a^2 t^4 / 4`` per axis.
    """
    return PathPredictor(horizons, acceleration_std)(np.asarray(x, float), np.asarray(P, float))
