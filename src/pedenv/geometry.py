"""Pure, vectorized camera geometry: viewing rays, ray intersection, projection, rotations."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TypeVar, overload

import numpy as np
from scipy.spatial.transform import Rotation

#: Entries of 2x2 matrices: arrays of one shape, or scalars (:func:`inverse_2x2_entries`).
Entries = TypeVar("Entries", np.ndarray, float)


def pixel_rays(pixels: np.ndarray, intrinsics: np.ndarray, cam_to_world: np.ndarray) -> np.ndarray:
    """Unit viewing rays of pixels in the world frame (the paper's Eq. 3, with ``K^-1``).

    pixels: (..., 2) float, pixels. intrinsics: (3, 3). cam_to_world: (4, 4) or (3, 3) rotation.
    Returns (..., 3) unit vectors, world frame.
    """
    k_inv = inverse_intrinsics(intrinsics)
    rot = cam_to_world[:3, :3]
    m = rot @ k_inv
    d = pixels[..., 0:1] * m[:, 0] + pixels[..., 1:2] * m[:, 1] + m[:, 2]
    return unit_vectors(d)


def unit_vectors(d: np.ndarray) -> np.ndarray:
    """``d`` (..., 3) scaled to unit length along the last axis, without overflow.

    Each vector is first divided by its largest absolute component, so the norm of
    components up to 1e308 does not overflow to inf (``np.linalg.norm`` squares them).
    A zero vector stays zero.
    """
    scale = np.max(np.abs(d), axis=-1, keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    d = d / scale
    norm = np.linalg.norm(d, axis=-1, keepdims=True)
    return d / np.where(norm > 0, norm, 1.0)


def inverse_intrinsics(k: np.ndarray) -> np.ndarray:
    """Inverse of an upper-triangular (3, 3) camera matrix, in closed form.

    ``np.linalg.inv`` goes through LAPACK, which costs far more than these few
    multiplications for a 3x3 matrix.
    """
    fx, s, cx, fy, cy = k[0, 0], k[0, 1], k[0, 2], k[1, 1], k[1, 2]
    return np.array([[1.0 / fx, -s / (fx * fy), (s * cy - cx * fy) / (fx * fy)],
                     [0.0, 1.0 / fy, -cy / fy],
                     [0.0, 0.0, 1.0]]) / k[2, 2] if k[2, 0] == 0 and k[2, 1] == 0 and k[1, 0] == 0 else np.linalg.inv(k)


def inverse_2x2_entries(a: Entries, b: Entries, c: Entries, d: Entries) -> tuple[Entries, Entries, Entries, Entries]:
    """Entries ``(a', b', c', d')`` of the inverse of ``[[a, b], [c, d]]``, in closed form.

    a, b, c, d: arrays of one shape (or scalars), any unit. For a symmetric matrix pass
    ``b`` twice: ``b' == c'``. Singular matrices give inf or NaN (no check).
    Written on the entries so code that keeps 2x2 matrices as separate component arrays
    needs not stack them: on a few matrices a frame, stacking costs more than the arithmetic.
    """
    det = a * d - b * c
    return d / det, -b / det, -c / det, a / det


def inverse_2x2(m: np.ndarray) -> np.ndarray:
    """Inverse of a batch of (..., 2, 2) matrices in closed form (:func:`inverse_2x2_entries`)."""
    a, b, c, d = inverse_2x2_entries(m[..., 0, 0], m[..., 0, 1], m[..., 1, 0], m[..., 1, 1])
    return np.stack([np.stack([a, b], -1), np.stack([c, d], -1)], -2)


def closest_points(o1: np.ndarray, d1: np.ndarray, o2: np.ndarray, d2: np.ndarray,
                   min_sin: float = 1e-9) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Closest points between rays ``o1 + s d1`` and ``o2 + t d2`` (Eqs. 4-5).

    o1, o2: (..., 3) origins, metres; d1, d2: (..., 3) unit directions (broadcastable).
    Returns ``(s, t, midpoint, parallel)``: (...,) distances along each ray, (..., 3) the
    midpoint of the two closest points, and a (...,) bool mask of rays whose angle has a
    sine below ``min_sin``, where ``s``, ``t`` and the midpoint are NaN.
    """
    w0 = o1 - o2
    b = np.sum(d1 * d2, axis=-1)
    d = np.sum(d1 * w0, axis=-1)
    e = np.sum(d2 * w0, axis=-1)
    denom = 1.0 - b * b  # |d1 x d2|^2 for unit vectors
    parallel = denom < min_sin * min_sin
    safe = np.where(parallel, 1.0, denom)
    s = np.where(parallel, np.nan, (b * e - d) / safe)
    t = np.where(parallel, np.nan, (e - b * d) / safe)
    mid = 0.5 * ((o1 + s[..., None] * d1) + (o2 + t[..., None] * d2))
    return s, t, mid, parallel


def project(points: np.ndarray, intrinsics: np.ndarray, world_to_cam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Project world points to pixels (Eq. 6, written with ``K`` and the inverse extrinsics).

    points: (..., 3) world frame, metres. Returns ``(pixels (..., 2), depth (...,))``; depth is
    the optical z in metres, points with depth <= 0 are behind the camera.
    """
    cam = points @ world_to_cam[:3, :3].T + world_to_cam[:3, 3]
    depth = cam[..., 2]
    safe = np.where(np.abs(depth) < 1e-12, 1e-12, depth)
    uvw = cam @ intrinsics.T
    return uvw[..., :2] / safe[..., None], depth


def invert_transform(t: np.ndarray) -> np.ndarray:
    """Inverse of a (4, 4) rigid transform."""
    inv = np.eye(4)
    r = t[:3, :3]
    inv[:3, :3] = r.T
    inv[:3, 3] = -r.T @ t[:3, 3]
    return inv


def rotation_z(angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` radians about z (counter-clockwise seen from above)."""
    return Rotation.from_euler("z", angle).as_matrix()


def rotation_from_ypr(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """(3, 3) rotation from yaw about z, pitch about y, roll about x (radians, z-y-x order).

    ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (intrinsic z-y'-x''). In the vehicle frame (x forward,
    y left, z up) a positive pitch turns the nose down.
    """
    return Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()


def quaternion_to_rotation(q: Sequence[float] | np.ndarray) -> np.ndarray:
    """(3, 3) rotation of a quaternion ``[w, x, y, z]`` (normalised first; not zero)."""
    return Rotation.from_quat(np.asarray(q, float), scalar_first=True).as_matrix()


def rotation_to_quaternion(r: np.ndarray) -> np.ndarray:
    """Unit quaternion ``[w, x, y, z]`` with ``w >= 0`` of a (3, 3) rotation."""
    return Rotation.from_matrix(np.asarray(r, float)).as_quat(canonical=True, scalar_first=True)


@overload
def wrap_angle(angle: float) -> float: ...


@overload
def wrap_angle(angle: np.ndarray) -> np.ndarray: ...


def wrap_angle(angle: float | np.ndarray) -> float | np.ndarray:
    """Angle(s) wrapped to [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi
