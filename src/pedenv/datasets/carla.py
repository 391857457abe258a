"""Reader of the paper's CARLA recordings (the layout below).

::

    <root>/scene<N>/data/data_<frame>.npy   # one pickled dict per frame
    <root>/scene<N>/rgb/img_<frame>.png     # the camera image of that frame

Unreal's left-handed axes and degrees are converted here (:mod:`pedenv.datasets.carla_axes`),
the 20 bones are mapped to COCO-17 (:mod:`pedenv.datasets.carla_bones`). Recordings run at
10 Hz: a frame's timestamp is ``(frame - first frame) / 10`` seconds, so a gap in the frame
numbers is elapsed time (and a warning naming the files on either side).
"""

from __future__ import annotations

import re
import struct
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from pedenv.datasets.carla_axes import cam_to_world_from_unreal, ego_from_unreal, points_from_unreal
from pedenv.datasets.carla_bones import NUM_BONES, bones_to_coco, visible_keypoints
from pedenv.datasets.safe_npy import load_npy
from pedenv.errors import InputError, check_array
from pedenv.geometry import invert_transform
from pedenv.records import Camera, EgoPose, Frame, GroundTruth

#: Simulation rate of the recordings.
FRAME_RATE_HZ = 10.0

#: Keys the reader needs in every frame dict (``world2cam`` is the inverse of ``cam2world``).
REQUIRED_KEYS: tuple[str, ...] = ("2d_skel", "3d_skel", "pos_3d", "bbox_2d", "ego_pos", "intr_cam", "cam2world")

_FRAME_FILE = re.compile(r"^data_(\d+)\.npy$")


def natural_key(name: str) -> list:
    """Sort key putting ``scene2`` before ``scene10``."""
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", name)]


class CarlaDataset:
    """The scenes ``scene*/`` under ``data_root``, in natural order, as :class:`Frame` sequences.

    Every frame carries ground truth (positions from ``pos_3d``, boxes from ``bbox_2d``, the
    COCO-17 skeletons and their 3D bones; ids are -1: the recordings have none), so the
    ``ground-truth`` pose backend needs no image, as in the paper.
    """

    name = "carla"
    default_pose_backend = "ground-truth"

    def __init__(self, data_root: str | Path) -> None:
        self.root = Path(data_root)
        if not self.root.is_dir():
            raise InputError(f"CARLA data root {self.root} does not exist or is not a folder")
        found = [p for p in self.root.glob("scene*") if (p / "data").is_dir()]
        self._scenes = {p.name: p for p in sorted(found, key=lambda p: natural_key(p.name))}
        if not self._scenes:
            raise InputError(
                f"{self.root}: no CARLA scenes (expected folders scene<N>/data/ with data_<frame>.npy files)"
            )

    def scene_names(self) -> list[str]:
        return list(self._scenes)

    def frames(self, scene: str) -> Iterator[Frame]:
        """The frames of ``scene`` in frame-number order; timestamps in seconds from the first."""
        if scene not in self._scenes:
            raise InputError(f"unknown CARLA scene {scene!r} in {self.root}; valid: {', '.join(self._scenes)}")
        folder = self._scenes[scene]
        files = frame_files(folder / "data")
        _warn_gaps(scene, files)
        images = [folder / "rgb" / f"img_{number}.png" for number, _ in files]
        missing = [p for p in images if not p.is_file()]
        if missing:
            warnings.warn(f"CARLA scene {scene}: image {missing[0]} is missing ({len(missing)} of {len(images)} images "
                          f"missing); those frames have no image and work with the ground-truth pose backend only",
                          stacklevel=2)
        first = files[0][0]
        for index, ((number, path), image) in enumerate(zip(files, images)):
            yield read_frame(path, index=index, timestamp=(number - first) / FRAME_RATE_HZ,
                             image_path=image if image.is_file() else None, scene=scene)


def frame_files(data_dir: Path) -> list[tuple[int, Path]]:
    """``(frame number, path)`` of the ``data_<frame>.npy`` files in ``data_dir``, by frame number."""
    files = sorted((int(m.group(1)), p) for p in data_dir.iterdir() if (m := _FRAME_FILE.match(p.name)))
    if not files:
        raise InputError(f"{data_dir}: no frame files data_<frame>.npy")
    return files


def _warn_gaps(scene: str, files: list[tuple[int, Path]]) -> None:
    for (n0, p0), (n1, p1) in zip(files, files[1:]):
        if n1 - n0 > 1:
            warnings.warn(f"CARLA scene {scene}: frame numbers jump from {n0} ({p0.name}) to {n1} ({p1.name}): "
                          f"{n1 - n0 - 1} frame(s) missing, counted as {(n1 - n0) / FRAME_RATE_HZ:.1f} s elapsed at "
                          f"{FRAME_RATE_HZ:g} Hz", stacklevel=3)


def load_record(path: Path) -> dict:
    """The frame dict stored in ``path``, checked for :data:`REQUIRED_KEYS`.

    The pickle inside is read by a restricted unpickler (numpy arrays, dtypes and plain
    containers only); a file naming anything else is refused with an InputError.
    """
    record = load_npy(path)  # never runs code from the file: see pedenv.datasets.safe_npy
    if not isinstance(record, dict):
        raise InputError(
            f"{path}: expected a pickled dict with keys {', '.join(REQUIRED_KEYS)}, got {type(record).__name__}"
        )
    missing = [k for k in REQUIRED_KEYS if k not in record]
    if missing:
        raise InputError(f"{path}: frame dict is missing key(s) {', '.join(missing)}")
    ego = record["ego_pos"]
    if not isinstance(ego, dict) or "xyz" not in ego or "yaw_pitch_roll" not in ego:
        raise InputError(f"{path}: 'ego_pos' must be a dict with keys xyz, yaw_pitch_roll")
    return record


def _stack(path: Path, record: dict, key: str, shape: tuple) -> np.ndarray:
    items = record[key]
    if not isinstance(items, (list, tuple, np.ndarray)):
        raise InputError(f"{path}: '{key}' must be a list, got {type(items).__name__}")
    wanted = "(N, " + ", ".join(map(str, shape)) + ")"
    try:
        rows = [np.asarray(v, float) for v in items]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{path}: '{key}' holds a non-numeric entry ({exc})") from None
    bad = next((i for i, r in enumerate(rows) if r.shape != shape), None)
    if bad is not None:
        raise InputError(f"{path}: '{key}' must have shape {wanted}; entry {bad} has shape {rows[bad].shape}")
    array = np.stack(rows) if rows else np.zeros((0, *shape))
    return check_array(f"{path}: '{key}'", array, (None, *shape))


def read_frame(path: Path, *, index: int, timestamp: float, image_path: Path | None = None, scene: str = "") -> Frame:
    """One recorded frame as a :class:`Frame` in pedenv's right-handed world."""
    record = load_record(path)
    k = check_array(f"{path}: 'intr_cam'", record["intr_cam"], (3, 3))
    ego = ego_from_unreal(check_array(f"{path}: 'ego_pos.xyz'", record["ego_pos"]["xyz"], (3,)),
                          check_array(f"{path}: 'ego_pos.yaw_pitch_roll'", record["ego_pos"]["yaw_pitch_roll"], (3,)))
    cam_to_world = cam_to_world_from_unreal(check_array(f"{path}: 'cam2world'", record["cam2world"], (4, 4)))
    width, height = _image_size(image_path, k)
    try:
        camera = Camera(k, width, height, invert_transform(ego) @ cam_to_world)
        ego_pose = EgoPose(ego[:3, 3], ego[:3, :3])
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None

    skel_2d = _stack(path, record, "2d_skel", (NUM_BONES, 2))
    skel_3d = _stack(path, record, "3d_skel", (NUM_BONES, 3))
    pos = _stack(path, record, "pos_3d", (3,))
    boxes = _stack(path, record, "bbox_2d", (4,))
    counts = {len(skel_2d), len(skel_3d), len(pos), len(boxes)}
    if len(counts) > 1:
        raise InputError(f"{path}: '2d_skel', '3d_skel', 'pos_3d', 'bbox_2d' list different numbers of pedestrians "
                         f"({len(skel_2d)}, {len(skel_3d)}, {len(pos)}, {len(boxes)})")
    truth = GroundTruth(
        ids=np.full(len(pos), -1, np.int64),
        positions=points_from_unreal(pos),
        boxes=boxes,
        keypoints=bones_to_coco(skel_2d),
        visible=visible_keypoints(skel_2d, width, height),
        keypoints_3d=bones_to_coco(points_from_unreal(skel_3d)),
    )
    return Frame(index=index, timestamp=timestamp, camera=camera, ego=ego_pose, ground_truth=truth,
                 image_path=image_path, scene=scene)


def _image_size(image_path: Path | None, intrinsics: np.ndarray) -> tuple[int, int]:
    """Width and height from the PNG header, else twice the principal point (it sits at the centre)."""
    if image_path is not None:
        with open(image_path, "rb") as f:
            head = f.read(24)
        if head[:8] == b"\x89PNG\r\n\x1a\n" and head[12:16] == b"IHDR":
            return struct.unpack(">II", head[16:24])
    return int(round(2 * intrinsics[0, 2])), int(round(2 * intrinsics[1, 2]))
