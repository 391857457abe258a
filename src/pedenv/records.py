"""Core records: small frozen dataclasses of fixed-shape arrays, validated on construction.

Conventions everywhere in the core (adapters convert at the boundary):

* world frame: right-handed, z up, metres; angles in radians; timestamps in seconds;
* vehicle frame: x forward, y left, z up, origin on the road under the vehicle;
* camera frame: optical, x right, y down, z forward (as nuScenes and OpenCV).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pedenv.errors import InputError, check_array
from pedenv.skeleton import NUM_KEYPOINTS

#: How far outside the image a detection's pixels may lie, in image sizes (widths for u,
#: heights for v): a keypoint or box edge beyond ``-k * width`` or ``(1 + k) * width`` (and
#: likewise for v) is refused by :class:`Frame` as corrupt input. Pose networks clip to the
#: image and a person partly outside it reaches at most a few image sizes beyond it, so 10
#: only refuses absurd values (1e155 px overflowed the geometry). Must be in [1, 1000];
#: raising it admits wilder keypoints.
MAX_PIXEL_OFFSET_IMAGE_SIZES = 10.0


def _frozen_set(obj: object, name: str, value: object) -> None:
    object.__setattr__(obj, name, value)


def check_pixels_in_bounds(where: str, detections: Detections, width: int, height: int,
                           image_sizes: float | None = None) -> None:
    """Raise InputError if a finite keypoint or a box edge of ``detections`` lies more than
    ``image_sizes`` (default :data:`MAX_PIXEL_OFFSET_IMAGE_SIZES`) image sizes outside the
    ``width`` x ``height`` image. NaN keypoints are data (confidence 0) and pass."""
    k = MAX_PIXEL_OFFSET_IMAGE_SIZES if image_sizes is None else image_sizes
    if isinstance(k, bool) or not isinstance(k, (int, float)) or not 1.0 <= k <= 1000.0:
        raise InputError(f"MAX_PIXEL_OFFSET_IMAGE_SIZES must be a number in [1, 1000], got {k!r}")
    low = np.array([-k * width, -k * height])
    high = np.array([(1.0 + k) * width, (1.0 + k) * height])
    kp = detections.keypoints
    # keypoints with confidence 0 (NaN turned into data) still must not be absurd
    bad_kp = ((kp < low) | (kp > high)).any(axis=(1, 2))
    boxes = detections.boxes.reshape(-1, 2, 2)
    bad_box = ((boxes < low) | (boxes > high)).any(axis=(1, 2))
    bad = np.flatnonzero(bad_kp | bad_box)
    if len(bad):
        i = int(bad[0])
        raise InputError(f"{where}: detection {i} has pixels absurdly far outside the {width}x{height} image "
                         f"(allowed: u in [{low[0]:g}, {high[0]:g}], v in [{low[1]:g}, {high[1]:g}]; "
                         f"MAX_PIXEL_OFFSET_IMAGE_SIZES = {k:g}); {len(bad)} detection(s) affected")


@dataclass(frozen=True)
class Detections:
    """2D skeletons of one image.

    keypoints: (N, 17, 2) float, pixels (u right, v down), COCO-17 order.
    confidences: (N, 17) float in [0, 1], per keypoint; 0 marks a keypoint not seen.
    boxes: (N, 4) float, pixels ``[u_min, v_min, u_max, v_max]``; defaults to the box
        around the keypoints whose confidence is above 0.
    scores: (N,) float in [0, 1], per person; defaults to the mean keypoint confidence.

    NaN keypoints are data, not an error: they get confidence 0 and are ignored.
    """

    keypoints: np.ndarray
    confidences: np.ndarray
    # None (the default) is replaced in __post_init__: after construction both are arrays
    boxes: np.ndarray = None  # type: ignore[assignment]
    scores: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        kp = check_array("keypoints", self.keypoints, (None, NUM_KEYPOINTS, 2), finite=False)
        n = kp.shape[0]
        conf = check_array("confidences", self.confidences, (n, NUM_KEYPOINTS), finite=False)
        bad = ~np.isfinite(kp).all(axis=2) | ~np.isfinite(conf)
        if bad.any():
            kp = np.where(bad[..., None], 0.0, kp)
            conf = np.where(bad, 0.0, conf)
        conf = np.clip(conf, 0.0, 1.0)
        boxes = boxes_from_keypoints(kp, conf > 0) if self.boxes is None else check_array("boxes", self.boxes, (n, 4))
        if np.any(boxes[:, 2] < boxes[:, 0]) or np.any(boxes[:, 3] < boxes[:, 1]):
            raise InputError("boxes must be [u_min, v_min, u_max, v_max] with max >= min")
        scores = conf.mean(axis=1) if self.scores is None else check_array("scores", self.scores, (n,))
        _frozen_set(self, "keypoints", kp)
        _frozen_set(self, "confidences", conf)
        _frozen_set(self, "boxes", boxes)
        _frozen_set(self, "scores", scores)

    def __len__(self) -> int:
        return self.keypoints.shape[0]

    @classmethod
    def empty(cls) -> Detections:
        return cls(np.zeros((0, NUM_KEYPOINTS, 2)), np.zeros((0, NUM_KEYPOINTS)))

    def take(self, index: np.ndarray) -> Detections:
        """The detections at ``index`` (an int array or boolean mask)."""
        return Detections(self.keypoints[index], self.confidences[index], self.boxes[index], self.scores[index])

    @classmethod
    def concat(cls, parts: Sequence[Detections]) -> Detections:
        """One :class:`Detections` of several of the same image, in order (none: empty)."""
        parts = [d for d in parts if len(d)]
        if not parts:
            return cls.empty()
        return cls(*(np.concatenate([getattr(d, k) for d in parts])
                     for k in ("keypoints", "confidences", "boxes", "scores")))


@dataclass(frozen=True)
class PredictedTracks:
    """The live tracks where the model expects them in the next frame, before it is added: what
    detection is given to search for people it would otherwise miss
    (:meth:`pedenv.model.PedestrianEnvironmentModel.predict_tracks`).

    ids: (T,) int64 track ids (a negative id: a person no track holds, searched again).
    boxes: (T, 4) float, pixels of the next frame ``[u_min, v_min, u_max, v_max]``.
    hits: (T,) int64, detections of each track so far.
    """

    ids: np.ndarray
    boxes: np.ndarray
    hits: np.ndarray

    def __post_init__(self) -> None:
        boxes = check_array("predicted boxes", self.boxes, (None, 4), finite=False)
        n = len(boxes)
        _frozen_set(self, "boxes", boxes)
        _frozen_set(self, "ids", check_array("track ids", self.ids, (n,), dtype=np.int64))
        _frozen_set(self, "hits", check_array("track hits", self.hits, (n,), dtype=np.int64))

    def __len__(self) -> int:
        return len(self.ids)

    @classmethod
    def none(cls) -> PredictedTracks:
        return cls(np.zeros(0, np.int64), np.zeros((0, 4)), np.zeros(0, np.int64))


def boxes_from_keypoints(keypoints: np.ndarray, visible: np.ndarray) -> np.ndarray:
    """Box around the visible keypoints: (N, 17, 2) pixels, (N, 17) bool -> (N, 4) pixels.

    A person with no visible keypoint gets the box around all of them.
    """
    visible = visible & np.isfinite(keypoints).all(axis=2)
    none = ~visible.any(axis=1)
    visible = visible | none[:, None]
    big = np.finfo(np.float64).max
    u, v = keypoints[..., 0], keypoints[..., 1]
    return np.stack(
        [np.where(visible, u, big).min(1), np.where(visible, v, big).min(1),
         np.where(visible, u, -big).max(1), np.where(visible, v, -big).max(1)],
        axis=1,
    ) if len(keypoints) else np.zeros((0, 4))


#: How a camera is mounted: ``vehicle`` (on a moving vehicle whose pitch, roll and height
#: over the road change as it drives) or ``static`` (fixed to the ground: an
#: infrastructure camera, a parked vehicle; its pitch, roll and height are exact).
MOUNTS = ("vehicle", "static")


@dataclass(frozen=True)
class Camera:
    """A pinhole camera mounted on the vehicle (images already undistorted).

    intrinsics: (3, 3) float, pixels.
    width, height: image size in pixels.
    cam_to_vehicle: (4, 4) float, optical camera frame -> vehicle frame, metres.
    mount: one of :data:`MOUNTS`. A ``static`` camera's vehicle frame is fixed to the
        ground: its road plane (vehicle z = 0) is exact, so the fused method trusts the
        ground contact at any range its pixel noise allows, and the tracker does not
        compensate ego motion.
    """

    intrinsics: np.ndarray
    width: int
    height: int
    cam_to_vehicle: np.ndarray = field(default_factory=lambda: default_cam_to_vehicle())
    mount: str = "vehicle"

    def __post_init__(self) -> None:
        if self.mount not in MOUNTS:
            raise InputError(f"camera mount must be one of {', '.join(MOUNTS)}, got {self.mount!r}")
        k = check_array("intrinsics", self.intrinsics, (3, 3))
        if abs(np.linalg.det(k)) < 1e-9 or k[0, 0] <= 0 or k[1, 1] <= 0:
            raise InputError(
                f"intrinsics must be an invertible camera matrix with positive focal lengths, got {k.tolist()}"
            )
        if int(self.width) <= 0 or int(self.height) <= 0:
            raise InputError(f"image size must be positive, got {self.width}x{self.height}")
        t = check_array("cam_to_vehicle", self.cam_to_vehicle, (4, 4))
        _check_rotation("cam_to_vehicle", t[:3, :3])
        _frozen_set(self, "intrinsics", k)
        _frozen_set(self, "cam_to_vehicle", t)
        _frozen_set(self, "width", int(self.width))
        _frozen_set(self, "height", int(self.height))

    @property
    def static(self) -> bool:
        """True for a camera fixed to the ground (``mount == "static"``)."""
        return self.mount == "static"

    @property
    def hfov(self) -> float:
        """Horizontal field of view in radians."""
        return 2.0 * float(np.arctan(self.width / (2.0 * self.intrinsics[0, 0])))

    @classmethod
    def from_fov(cls, width: int = 1600, height: int = 900, hfov_deg: float = 64.5, *,
                 height_m: float = 1.5, forward_m: float = 0.0) -> Camera:
        """A camera looking straight ahead along the vehicle's x axis, principal point centred."""
        f = width / (2.0 * np.tan(np.radians(hfov_deg) / 2.0))
        k = np.array([[f, 0.0, width / 2.0], [0.0, f, height / 2.0], [0.0, 0.0, 1.0]])
        return cls(k, width, height, default_cam_to_vehicle(height_m, forward_m))


#: Optical camera axes (x right, y down, z forward) expressed in the vehicle frame.
OPTICAL_TO_VEHICLE = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def default_cam_to_vehicle(height_m: float = 1.5, forward_m: float = 0.0) -> np.ndarray:
    """A forward-looking camera ``height_m`` above the road and ``forward_m`` ahead of the origin."""
    t = np.eye(4)
    t[:3, :3] = OPTICAL_TO_VEHICLE
    t[:3, 3] = [forward_m, 0.0, height_m]
    return t


def _check_rotation(name: str, r: np.ndarray) -> None:
    if not np.allclose(r @ r.T, np.eye(3), atol=1e-4) or np.linalg.det(r) < 0:
        raise InputError(f"{name} rotation must be orthonormal and right-handed")


@dataclass(frozen=True)
class EgoPose:
    """The vehicle's pose: vehicle frame -> world frame.

    translation: (3,) float, world frame, metres (the vehicle origin, on the road).
    rotation: (3, 3) float, vehicle -> world.
    """

    translation: np.ndarray
    rotation: np.ndarray

    def __post_init__(self) -> None:
        t = check_array("ego translation", self.translation, (3,))
        r = check_array("ego rotation", self.rotation, (3, 3))
        _check_rotation("ego", r)
        _frozen_set(self, "translation", t)
        _frozen_set(self, "rotation", r)

    @property
    def yaw(self) -> float:
        """Heading in radians, counter-clockwise from the world x axis seen from above."""
        return float(np.arctan2(self.rotation[1, 0], self.rotation[0, 0]))

    @property
    def matrix(self) -> np.ndarray:
        """(4, 4) vehicle -> world."""
        m = np.eye(4)
        m[:3, :3] = self.rotation
        m[:3, 3] = self.translation
        return m

    @classmethod
    def from_xy_yaw(cls, x: float, y: float, yaw: float, z: float = 0.0) -> EgoPose:
        c, s = np.cos(yaw), np.sin(yaw)
        return cls(np.array([x, y, z], float), np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))


@dataclass(frozen=True)
class GroundTruth:
    """Ground-truth pedestrians of one frame.

    ids: (M,) int64, identity over the scene (-1 where the dataset has none).
    positions: (M, 3) float, world frame, metres: the ground point under the person.
    boxes: (M, 4) float, pixels ``[u_min, v_min, u_max, v_max]``.
    keypoints: optional (M, 17, 2) float, pixels: exact 2D skeletons where the data has them.
    visible: optional (M, 17) bool, which of those keypoints are seen.
    heights: optional (M,) float, metres: the persons' body heights where known.
    keypoints_3d: optional (M, 17, 3) float, world frame, metres: the 3D skeletons.
    """

    ids: np.ndarray
    positions: np.ndarray
    boxes: np.ndarray
    keypoints: np.ndarray | None = None
    visible: np.ndarray | None = None
    heights: np.ndarray | None = None
    keypoints_3d: np.ndarray | None = None

    def __post_init__(self) -> None:
        ids = check_array("ground truth ids", self.ids, (None,), dtype=np.int64)
        m = ids.shape[0]
        _frozen_set(self, "ids", ids)
        _frozen_set(self, "positions", check_array("ground truth positions", self.positions, (m, 3)))
        _frozen_set(self, "boxes", check_array("ground truth boxes", self.boxes, (m, 4)))
        if self.keypoints is not None:
            _frozen_set(self, "keypoints", check_array("ground truth keypoints", self.keypoints, (m, NUM_KEYPOINTS, 2)))
            vis = np.ones((m, NUM_KEYPOINTS), bool) if self.visible is None else self.visible
            _frozen_set(self, "visible", check_array("ground truth visible", vis, (m, NUM_KEYPOINTS), dtype=bool))
        if self.heights is not None:
            _frozen_set(self, "heights", check_array("ground truth heights", self.heights, (m,)))
        if self.keypoints_3d is not None:
            _frozen_set(
                self, "keypoints_3d", check_array("ground truth keypoints_3d", self.keypoints_3d, (m, NUM_KEYPOINTS, 3))
            )

    def __len__(self) -> int:
        return self.ids.shape[0]

    @classmethod
    def empty(cls) -> GroundTruth:
        return cls(np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros((0, 4)))


@dataclass(frozen=True)
class Frame:
    """One camera frame with everything the environment model needs.

    index: position of the frame in its sequence.
    timestamp: seconds.
    camera, ego: the camera and the vehicle's pose at ``timestamp``.
    detections: the 2D skeletons, or None until a pose backend has run.
    ground_truth: the ground-truth pedestrians, or None where the frame has no labels.
    image: optional (H, W, 3) uint8 RGB; image_path: where the image lives on disk.
    scene: name of the scene or recording the frame belongs to.
    """

    index: int
    timestamp: float
    camera: Camera
    ego: EgoPose
    detections: Detections | None = None
    ground_truth: GroundTruth | None = None
    image: np.ndarray | None = None
    image_path: Path | None = None
    scene: str = ""

    def __post_init__(self) -> None:
        try:
            ts = float(self.timestamp)
        except (TypeError, ValueError):
            raise InputError(f"frame {self.index}: timestamp must be a number, got {self.timestamp!r}") from None
        if not np.isfinite(ts):
            raise InputError(f"frame {self.index}: timestamp must be finite, got {ts}")
        _frozen_set(self, "timestamp", ts)
        for name, kind in (("camera", Camera), ("ego", EgoPose)):
            if not isinstance(getattr(self, name), kind):
                raise InputError(
                    f"frame {self.index}: {name} must be a {kind.__name__}, got {type(getattr(self, name)).__name__}"
                )
        if self.detections is not None and not isinstance(self.detections, Detections):
            raise InputError(f"frame {self.index}: detections must be Detections, got {type(self.detections).__name__}")
        if self.detections is not None:
            check_pixels_in_bounds(f"frame {self.index}", self.detections, self.camera.width, self.camera.height)
        if self.image_path is not None:
            _frozen_set(self, "image_path", Path(self.image_path))

    @property
    def cam_to_world(self) -> np.ndarray:
        """(4, 4) optical camera frame -> world frame."""
        return self.ego.matrix @ self.camera.cam_to_vehicle


@dataclass(frozen=True)
class Scene:
    """A named sequence of frames in time order (one recording, one synthetic scenario)."""

    name: str
    frames: tuple[Frame, ...]
    description: str = ""

    def __post_init__(self) -> None:
        _frozen_set(self, "frames", tuple(self.frames))
        for prev, cur in zip(self.frames, self.frames[1:]):
            if cur.timestamp <= prev.timestamp:
                raise InputError(
                    f"scene {self.name!r}: frame {cur.index} timestamp {cur.timestamp:.6f} s is not after "
                    f"frame {prev.index} ({prev.timestamp:.6f} s)")

    def __len__(self) -> int:
        return len(self.frames)
