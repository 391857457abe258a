"""KITTI tracking as a pedenv dataset: ``pedenv evaluate --dataset kitti --data-root <kitti>``.

``data_root`` is a KITTI tracking folder holding ``training/`` (or the ``training/`` folder
itself, or a folder holding ``tracking_mini/training``) with ``image_02/<seq>/``,
``calib/<seq>.txt``, ``label_02/<seq>.txt`` and optionally
``ego_poses_orbslam3/<seq>/CameraTrajectory.txt``. One scene per sequence; frames are the
images present (10 Hz timestamps from the frame number).

Frames (converted here, once):
- world: the vehicle frame at frame 0 (x forward, y left, z up, metres, right-handed),
  origin on the ground under the reference camera (cam0), which sits ``camera_height_m``
  (1.65 m, the KITTI setup) above it;
- ego poses: the ORB-SLAM3 camera trajectory (``T_world_from_cam0`` in KITTI's camera axes)
  taken into that world; without a trajectory the ego stands still;
- camera: image_02 (intrinsics ``P2[:, :3]``, 6 cm left of cam0);
- ground truth: ``Pedestrian`` labels, bottom-face centres of their 3D boxes as positions,
  track ids as ids, 2D boxes, box heights as body heights.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from pedenv.datasets import kitti_files as kitti
from pedenv.errors import InputError
from pedenv.images import image_size
from pedenv.records import Camera, EgoPose, Frame, GroundTruth
from pedenv.validation import check_number

#: Optical / KITTI camera axes (x right, y down, z forward) -> vehicle axes (x forward, y left, z up).
CAMERA_TO_VEHICLE_AXES = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
FRAME_RATE_HZ = 10.0


def cam0_to_vehicle(camera_height_m: float) -> np.ndarray:
    """(4, 4) KITTI reference-camera coordinates -> vehicle frame (origin on the ground below cam0)."""
    t = np.eye(4)
    t[:3, :3] = CAMERA_TO_VEHICLE_AXES
    t[2, 3] = camera_height_m
    return t


def _training_dir(root: Path) -> Path:
    for candidate in (root, root / "training", root / "tracking_mini" / "training"):
        if (candidate / "image_02").is_dir() and (candidate / "calib").is_dir():
            return candidate
    raise InputError(
        f"{root}: no KITTI tracking folder (expected training/image_02, training/calib, training/label_02)"
    )


class KittiTrackingDataset:
    """KITTI tracking sequences as scenes of :class:`~pedenv.records.Frame` (module doc)."""

    name = "kitti"
    default_pose_backend = "onnx"

    def __init__(self, data_root: str | Path, camera_height_m: float = 1.65) -> None:
        check_number("camera_height_m", camera_height_m, 0.1, 10.0)
        self.training = _training_dir(Path(data_root))
        self.camera_height_m = float(camera_height_m)

    def scene_names(self) -> list[str]:
        return kitti.tracking_sequence_names(self.training)

    def frames(self, scene: str) -> Iterator[Frame]:
        if scene not in self.scene_names():
            raise InputError(f"{self.training}: no sequence {scene!r}; found {', '.join(self.scene_names())}")
        seq = kitti.read_tracking_sequence(self.training, scene)
        if not seq.frames:
            return
        first = seq.image_path(seq.frames[0])
        width, height = image_size(first)  # from the header; any file name (pedenv.images)
        to_vehicle = cam0_to_vehicle(self.camera_height_m)
        cam2 = np.eye(4)
        cam2[:3, 3] = seq.calib.cam2_position
        camera = Camera(seq.calib.K, width, height, to_vehicle @ cam2)
        from_vehicle = np.linalg.inv(to_vehicle)
        for index, frame in enumerate(seq.frames):
            cam0_pose = seq.poses[frame] if seq.poses is not None else np.eye(4)
            world_from_cam0 = to_vehicle @ cam0_pose  # the world is the vehicle frame at frame 0
            vehicle = world_from_cam0 @ from_vehicle
            ego = EgoPose(vehicle[:3, 3].copy(), vehicle[:3, :3].copy())
            people = seq.labels.in_frame(frame).of_type("Pedestrian")
            points = np.c_[people.locations, np.ones(len(people))] @ world_from_cam0.T
            truth = GroundTruth(people.track_id.astype(np.int64), points[:, :3], people.boxes.astype(float),
                                heights=people.dimensions[:, 0].astype(float))
            yield Frame(index, frame / FRAME_RATE_HZ, camera, ego, ground_truth=truth,
                        image_path=seq.image_path(frame), scene=scene)
