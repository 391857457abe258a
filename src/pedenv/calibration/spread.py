"""The estimate's uncertainty carried into world positions: one error shared by every person.

A position on the ground was seen at a pixel; under slightly different camera parameters the
same pixel cuts the ground elsewhere. The Jacobian of that cut by (f, H, tilt, roll), taken
numerically, carries the estimate's covariance to each position's x-y covariance.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.geometry import camera_rotation, ground_points, intrinsics, project
from pedenv.records import EgoPose
from pedenv.state import EnvironmentState

#: Parameter steps of the numerical Jacobian: focal length (px), height (m), tilt and roll (rad).
STEPS = np.array([1.0, 0.01, 1e-4, 1e-4])


def _ground(params: np.ndarray, pixels: np.ndarray, centre: tuple[float, float]) -> np.ndarray:
    f, h, tilt, roll = params
    return ground_points(pixels, intrinsics(f, centre), camera_rotation(tilt, roll), h)[:, :2]


def calibration_covariances(positions: np.ndarray, estimate: CameraEstimate) -> np.ndarray:
    """(N, 2, 2) m^2: the x-y covariance the estimate's uncertainty adds to each ground position.

    positions: (N, 3) world frame (the estimated camera's), metres.
    """
    positions = np.asarray(positions, float).reshape(-1, 3)
    base = np.array([estimate.focal, estimate.height, estimate.tilt, estimate.roll])
    k, r = intrinsics(estimate.focal, estimate.centre), camera_rotation(estimate.tilt, estimate.roll)
    pixels = project(np.c_[positions[:, :2], np.zeros(len(positions))], k, r, estimate.height)
    jac = np.zeros((len(positions), 2, 4))
    for i, step in enumerate(STEPS):
        up, down = base.copy(), base.copy()
        up[i] += step
        down[i] -= step
        jac[:, :, i] = (_ground(up, pixels, estimate.centre) - _ground(down, pixels, estimate.centre)) / (2 * step)
    extra = np.einsum("nij,jk,nlk->nil", jac, estimate.covariance, jac)
    return np.nan_to_num(extra, nan=0.0, posinf=0.0)


def widen_state(state: EnvironmentState, estimate: CameraEstimate, ego: EgoPose | None = None) -> EnvironmentState:
    """``state`` (an :class:`~pedenv.state.EnvironmentState`) with every pedestrian's covariance
    widened by :func:`calibration_covariances`; ``ego``: the frame's vehicle -> world pose (the
    estimate's ground frame is the vehicle's moved to under the camera, :attr:`CameraEstimate.position`;
    None: the world's)."""
    people = state.pedestrians
    if not len(people):
        return state
    if ego is None:
        extra = calibration_covariances(people.positions, estimate)
    else:
        local = (people.positions - ego.translation) @ ego.rotation  # rows: R^T (p - t), the vehicle frame
        local[:, :2] -= estimate.position  # the ground under the camera
        turn = ego.rotation[:2, :2]
        extra = turn @ calibration_covariances(local, estimate) @ turn.T
    covariances = people.covariances + extra
    return dataclasses.replace(state, pedestrians=dataclasses.replace(people, covariances=covariances))
