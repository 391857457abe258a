"""Estimated MOT17 cameras (UCMCTrack's ``cam_para`` files) and static-camera scenes made from them.

A ``cam_para`` file (UCMCTrack, MIT licence) holds three blocks of plain numbers::

    RotationMatrices        3 rows of 3: R, world -> camera
    TranslationVectors      1 row of 3:  T, world -> camera, millimetres
    IntrinsicMatrix         3 rows of 3: K, pixels (no distortion)

A world point ``X`` (metres; z up, the ground at z = 0) maps to the optical camera frame as
``R @ X + T / 1000`` and to the pixel ``K @ x_cam`` over its third coordinate.

:func:`static_camera` turns it into a :class:`~pedenv.records.Camera` whose vehicle frame
stands on the ground under the camera centre, x along the optical axis seen from above, z
up; :func:`mot17_static_scene` makes a MOT17 sequence a scene with that camera, the
identity ego pose and, as ground truth, the ground-truth boxes' bottom centres cut with
the ground plane (the MOTChallenge 3D / PETS practice: as good as the camera estimate and
the box bottoms).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pedenv.datasets import mot17
from pedenv.errors import InputError, read_text
from pedenv.records import Camera, EgoPose, Frame, GroundTruth, Scene

BLOCKS = ("RotationMatrices", "TranslationVectors", "IntrinsicMatrix")
#: A box bottom whose ray meets the ground farther than this (metres) from the camera, or
#: not at all (above the horizon), gives no ground truth: the person is left out.
MAX_GROUND_RANGE_M = 200.0


@dataclass(frozen=True)
class CameraParameters:
    """One ``cam_para`` file. rotation: (3, 3) world -> camera. translation: (3,) world ->
    camera, metres. intrinsics: (3, 3) pixels. The world has z up and the ground at z = 0."""

    rotation: np.ndarray
    translation: np.ndarray
    intrinsics: np.ndarray

    @property
    def centre(self) -> np.ndarray:
        """(3,) the camera centre, world, metres."""
        return -self.rotation.T @ self.translation


def read_camera_parameters(path: str | Path) -> CameraParameters:
    """Read a UCMCTrack ``cam_para`` file (module doc); every error names the file and block."""
    path = Path(path)
    blocks: dict[str, list[list[float]]] = {}
    current = None
    for n, line in enumerate(read_text(path, "the camera parameters").splitlines(), start=1):
        words = line.split()
        if not words:
            continue
        if words[0] in BLOCKS and len(words) == 1:
            current = blocks.setdefault(words[0], [])
            continue
        if current is None:
            raise InputError(f"{path}: line {n} holds numbers before a block name ({', '.join(BLOCKS)})")
        try:
            current.append([float(w) for w in words])
        except ValueError:
            raise InputError(f"{path}: line {n} must hold numbers, got {line.strip()!r}") from None
    shapes = {"RotationMatrices": (3, 3), "TranslationVectors": (1, 3), "IntrinsicMatrix": (3, 3)}
    arrays = {}
    for name, shape in shapes.items():
        rows = blocks.get(name)
        if not rows or any(len(r) != shape[1] for r in rows) or len(rows) != shape[0]:
            raise InputError(f"{path}: block {name} must hold {shape[0]} row(s) of {shape[1]} numbers, got {rows}")
        arrays[name] = np.array(rows, float)
        if not np.all(np.isfinite(arrays[name])):
            raise InputError(f"{path}: block {name} holds NaN or inf")
    r = arrays["RotationMatrices"]
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-3) or np.linalg.det(r) < 0:
        raise InputError(f"{path}: RotationMatrices is not a right-handed rotation (det {np.linalg.det(r):.4f})")
    return CameraParameters(r, arrays["TranslationVectors"][0] / 1000.0, arrays["IntrinsicMatrix"])


def static_camera(params: CameraParameters, width: int, height: int, mount: str = "static") -> Camera:
    """The camera of ``params`` for a ``width`` x ``height`` image, in a vehicle frame on the
    ground under its centre (x: the optical axis seen from above, z up); ``mount`` ``static``
    (the default) or ``vehicle``. The ego pose of its frames is the identity."""
    cam_to_world = params.rotation.T
    forward = cam_to_world[:2, 2]
    if np.linalg.norm(forward) < 1e-6:
        raise InputError("the camera looks straight down: no forward direction for its vehicle frame")
    x = np.append(forward / np.linalg.norm(forward), 0.0)
    z = np.array([0.0, 0.0, 1.0])
    world_to_vehicle = np.stack([x, np.cross(z, x), z])  # rows: the vehicle axes in the world
    t = np.eye(4)
    t[:3, :3] = world_to_vehicle @ cam_to_world
    t[2, 3] = params.centre[2]
    return Camera(params.intrinsics, width, height, t, mount)


def ground_points(camera: Camera, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Where the rays of ``pixels`` (N, 2) meet the ground (vehicle z = 0): points (N, 3),
    vehicle frame, metres, and (N,) bool where the ray meets it within :data:`MAX_GROUND_RANGE_M`."""
    homogeneous = np.column_stack([pixels, np.ones(len(pixels))])
    rays = homogeneous @ np.linalg.inv(camera.intrinsics).T @ camera.cam_to_vehicle[:3, :3].T
    origin = camera.cam_to_vehicle[:3, 3]
    down = rays[:, 2] < -1e-9
    s = np.where(down, -origin[2] / np.where(down, rays[:, 2], -1.0), 0.0)
    points = origin + s[:, None] * rays
    points[:, 2] = 0.0
    near = down & (np.linalg.norm(points[:, :2] - origin[:2], axis=1) <= MAX_GROUND_RANGE_M)
    return points, near


def mot17_static_scene(folder: str | Path, cam_para: str | Path, mount: str = "static") -> Scene:
    """The MOT17 sequence in ``folder`` as a scene seen by the camera of ``cam_para``
    (:func:`static_camera` with ``mount``): images read from disk, ego at the identity,
    timestamps ``(frame - 1) / frameRate`` s, and as ground truth every evaluated class-1
    box whose bottom centre meets the ground within :data:`MAX_GROUND_RANGE_M`."""
    seq = mot17.read_sequence(folder)
    info = seq.info
    camera = static_camera(read_camera_parameters(cam_para), info.width, info.height, mount)
    ego = EgoPose(np.zeros(3), np.eye(3))
    frames = []
    for index, number in enumerate(seq.frames):
        rows = seq.pedestrians.in_frame(number)
        rows = rows.take(rows.consider)
        feet = np.column_stack([0.5 * (rows.boxes[:, 0] + rows.boxes[:, 2]), rows.boxes[:, 3]])
        points, near = ground_points(camera, feet)
        truth = GroundTruth(rows.ids[near], points[near], rows.boxes[near])
        frames.append(Frame(index, (number - 1) / info.frame_rate, camera, ego, ground_truth=truth,
                            image_path=seq.image_path(number), scene=info.name))
    return Scene(info.name, tuple(frames), f"{info.name} with the UCMCTrack camera estimate, mount {mount}")
