"""Whole KITTI tracking drives, every frame: ``pedenv evaluate --dataset kitti-tracking --data-root DIR``.

``DIR`` is a KITTI tracking folder holding ``training/`` (or ``training/`` itself) with
``calib/<seq>.txt``, ``label_02/<seq>.txt`` and the ego poses, either
``ego_poses_orbslam3/<seq>/CameraTrajectory.txt`` (preferred) or ``oxts/<seq>.txt`` (GPS/IMU);
``image_02/<seq>/`` is optional. One scene per sequence with labels, calibration and poses;
every frame of the poses is a frame (10 Hz). The frames are those of :mod:`pedenv.datasets.kitti`
(world: the vehicle frame at frame 0; camera: image_02), converted here once.

Without images the skeletons are rendered from the labels (:mod:`pedenv.synthetic.labelled`:
each ``Pedestrian`` box's bottom centre, height and ``rotation_y``, the gait from its labelled
motion, ``occluded`` hiding keypoints and causing misses) and the default pose backend is the
detector model fitted to the real network in the default ``far`` detection mode, with its false
positives per image area (``detector-model:yolo11n-pose-far-kitti``): every figure is **real
motion, modelled perception**.
The ground-truth boxes are then the rendered skeletons' boxes (clipped to the image), as on the
synthetic scenes, so that the tracking metrics match a detection to the person it was rendered
from (the labelled 2D boxes reach from head top to soles and arms, a skeleton's only from eyes to
ankles: their median IoU is 0.51). The positions are the labelled ones. With ``--pose-backend
onnx`` the real network runs on the frames that have an image (only those), scored against the
labelled boxes.

Refused with one line naming the file (and line): a sequence without poses, labels or ``P2``,
a label file without a line, a label frame or image beyond the poses, OXTS that jumps.
"""

from __future__ import annotations

import re
import zlib
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from pedenv.datasets import kitti_files as kitti
from pedenv.datasets.kitti import FRAME_RATE_HZ, cam0_to_vehicle
from pedenv.datasets.kitti_oxts import read_oxts_camera_poses
from pedenv.errors import InputError
from pedenv.images import image_size
from pedenv.records import Camera, EgoPose, Frame, GroundTruth, boxes_from_keypoints
from pedenv.synthetic.labelled import occlusion_visibility, render_skeletons, track_motion
from pedenv.validation import check_number

#: What every figure on these drives is, in metrics.json and the printed title.
PERCEPTION_NOTE = "real motion, modelled perception (skeletons rendered from the labels' 3D boxes)"
#: Where the ego poses come from (``ego_poses``): ORB-SLAM3's stereo trajectory first, or GPS/IMU (OXTS) first.
EGO_POSE_SOURCES = ("orbslam3", "oxts")
PERCEPTION_NOTE_IMAGES = "real motion, real perception (the pose network on image_02)"


def training_dir(root: Path) -> Path:
    """The ``training/`` folder under ``root`` (or ``root`` itself) with ``label_02`` and ``calib``."""
    for candidate in (root, root / "training"):
        if (candidate / "label_02").is_dir() and (candidate / "calib").is_dir():
            return candidate
    raise InputError(f"{root}: no KITTI tracking folder (expected training/label_02, training/calib and "
                     "training/ego_poses_orbslam3 or training/oxts)")


class KittiDrivesDataset:
    """Whole KITTI tracking sequences, every frame, skeletons rendered from the labels (module doc)."""

    name = "kitti-tracking"
    default_pose_backend = "detector-model:yolo11n-pose-far-kitti"

    def __init__(self, data_root: str | Path, camera_height_m: float = 1.65, seed: int = 0,
                 images_only: bool = False, ego_poses: str = "orbslam3") -> None:
        check_number("camera_height_m", camera_height_m, 0.1, 10.0)
        if ego_poses not in EGO_POSE_SOURCES:
            raise InputError(f"ego_poses must be one of {', '.join(EGO_POSE_SOURCES)}, got {ego_poses!r}")
        self.training = training_dir(Path(data_root))
        self.camera_height_m = float(camera_height_m)
        self.seed = int(seed)
        self.images_only = bool(images_only)
        self.ego_poses = ego_poses

    @property
    def perception(self) -> str:
        return PERCEPTION_NOTE_IMAGES if self.images_only else PERCEPTION_NOTE

    def with_images_only(self) -> KittiDrivesDataset:
        """The same drives, only the frames with an image (for the real pose network)."""
        return KittiDrivesDataset(self.training, self.camera_height_m, self.seed, images_only=True,
                                  ego_poses=self.ego_poses)

    def scene_names(self) -> list[str]:
        return sorted(p.stem for p in (self.training / "label_02").glob("*.txt"))

    def frames(self, scene: str) -> Iterator[Frame]:
        if scene not in self.scene_names():
            raise InputError(f"{self.training}: no sequence {scene!r}; found {', '.join(self.scene_names())}")
        drive = read_drive(self.training, scene, oxts_first=self.ego_poses == "oxts")
        to_vehicle = cam0_to_vehicle(self.camera_height_m)
        cam2 = np.eye(4)
        cam2[:3, 3] = drive.calib.cam2_position
        camera = Camera(drive.calib.K, drive.width, drive.height, to_vehicle @ cam2)
        from_vehicle = np.linalg.inv(to_vehicle)
        world_from_cam0 = to_vehicle @ drive.poses  # (F, 4, 4): the world is the vehicle frame at frame 0
        people = drive.labels.of_type("Pedestrian")
        ground, skeletons = _people_in_world(people, world_from_cam0)
        crc = zlib.crc32(scene.encode())
        for frame in range(len(drive.poses)):
            image = drive.image_dir / f"{frame:06d}.png"
            if self.images_only and not image.is_file():
                continue
            rows = np.flatnonzero(people.frame == frame)
            vehicle = world_from_cam0[frame] @ from_vehicle
            ego = EgoPose(vehicle[:3, 3].copy(), vehicle[:3, :3].copy())
            rng = np.random.default_rng([self.seed & 0xFFFFFFFF, crc, frame, 7])
            uv, seen = _seen(drive, np.linalg.inv(world_from_cam0[frame]), skeletons[rows], people.occluded[rows], rng)
            boxes = people.boxes[rows] if self.images_only else np.clip(
                boxes_from_keypoints(uv, np.ones(uv.shape[:2], bool)), 0.0, [drive.width, drive.height] * 2)
            truth = GroundTruth(people.track_id[rows], ground[rows], boxes.astype(float), keypoints=uv, visible=seen,
                                heights=people.dimensions[rows, 0], keypoints_3d=skeletons[rows])
            yield Frame(frame, frame / FRAME_RATE_HZ, camera, ego, ground_truth=truth,
                        image_path=image if image.is_file() else None, scene=scene)


def _people_in_world(people: kitti.KittiLabels, world_from_cam0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ground points (N, 3) and rendered skeletons (N, 17, 3), world, metres, of the N labelled rows."""
    ground = np.einsum("nij,nj->ni", world_from_cam0[people.frame], np.c_[people.locations, np.ones(len(people))])
    speed, walked = track_motion(people.track_id, people.frame, ground[:, :2], FRAME_RATE_HZ)
    forward = np.c_[np.cos(people.rotation_y), np.zeros(len(people)), -np.sin(people.rotation_y)]  # KITTI's yaw
    forward = np.einsum("nij,nj->ni", world_from_cam0[people.frame, :3, :3], forward)
    heading = np.arctan2(forward[:, 1], forward[:, 0])
    skeletons = render_skeletons(ground[:, :3], heading, people.dimensions[:, 0], speed, walked, people.track_id)
    return ground[:, :3], skeletons


def _seen(drive: Drive, cam0_from_world: np.ndarray, skeletons: np.ndarray, occluded: np.ndarray,
          rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The skeletons (N, 17, 3) world projected into image_02: pixels (N, 17, 2) and seen (N, 17)."""
    pts = np.c_[skeletons.reshape(-1, 3), np.ones(17 * len(skeletons))] @ cam0_from_world.T
    uv = np.nan_to_num(drive.calib.project(pts[:, :3]).reshape(-1, 17, 2))
    inside = ((uv[..., 0] >= 0) & (uv[..., 0] < drive.width) & (uv[..., 1] >= 0) & (uv[..., 1] < drive.height)
              & (pts[:, 2].reshape(-1, 17) > 0.5))
    return uv, occlusion_visibility(inside, occluded, rng)


class Drive:
    """One sequence on disk: calibration, labels, (F, 4, 4) cam0 poses (world: cam0 at frame 0,
    KITTI camera axes), the image size and folder."""

    def __init__(self, calib: kitti.KittiCalib, labels: kitti.KittiLabels, poses: np.ndarray, size: tuple[int, int],
                 image_dir: Path) -> None:
        self.calib, self.labels, self.poses, self.image_dir = calib, labels, poses, image_dir
        self.width, self.height = size


def read_drive(training: Path, name: str, oxts_first: bool = False) -> Drive:
    """Read sequence ``name``: every check of the module doc, each naming its file. The poses: ORB-SLAM3's
    where there are both (OXTS's with ``oxts_first``), else the one there is."""
    calib = kitti.read_calib(training / "calib" / f"{name}.txt")
    label_file = training / "label_02" / f"{name}.txt"
    labels = kitti.read_labels(label_file)
    if not len(labels):
        raise InputError(f"{label_file}: no label lines (an empty sequence)")
    trajectory = training / "ego_poses_orbslam3" / name / "CameraTrajectory.txt"
    oxts = training / "oxts" / f"{name}.txt"
    if trajectory.is_file() and not (oxts_first and oxts.is_file()):
        poses, pose_file = kitti.read_camera_trajectory(trajectory), trajectory
    elif oxts.is_file():
        poses, pose_file = read_oxts_camera_poses(oxts, calib), oxts
    else:
        raise InputError(f"{training}: sequence {name} has no ego poses ({trajectory.relative_to(training)} or "
                         f"{oxts.relative_to(training)})")
    beyond = labels.frame >= len(poses)
    if beyond.any():
        row = int(np.flatnonzero(beyond)[0])
        raise InputError(f"{label_file}:{labels.line[row]}: frame {labels.frame[row]} lies beyond the "
                         f"{len(poses)} poses of {pose_file} (one line per frame)")
    image_dir = training / "image_02" / name
    images = sorted(image_dir.glob("*.png")) if image_dir.is_dir() else []
    for image in images:
        if not image.stem.isdigit() or int(image.stem) >= len(poses):
            raise InputError(f"{image}: not a frame of the {len(poses)} poses of {pose_file} (000012.png)")
    return Drive(calib, labels, poses, _image_size(training, name, images), image_dir)


def _image_size(training: Path, name: str, images: list[Path]) -> tuple[int, int]:
    """(width, height) px of image_02: from ORB-SLAM3's settings beside the poses, else an image."""
    settings = training / "ego_poses_orbslam3" / name / f"{name}.yaml"
    if settings.is_file():
        text = settings.read_text(encoding="utf-8", errors="replace")
        found = [re.search(rf"^\s*Camera\.{key}:\s*([0-9]+)\s*$", text, re.M) for key in ("width", "height")]
        if found[0] and found[1]:
            size = int(found[0].group(1)), int(found[1].group(1))
            if not all(16 <= s <= 20000 for s in size):
                raise InputError(f"{settings}: Camera.width/height must lie in [16, 20000], got {size}")
            return size
    if images:
        return image_size(images[0])
    raise InputError(f"{training}: sequence {name} has no image size (ego_poses_orbslam3/{name}/{name}.yaml with "
                     f"Camera.width and Camera.height, or an image in image_02/{name}/)")
