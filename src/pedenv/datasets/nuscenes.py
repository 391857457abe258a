"""nuScenes through the official devkit: every CAM_FRONT image of a scene as a :class:`Frame`.

Conventions converted here: timestamps in microseconds -> seconds; quaternions ``[w, x, y, z]``
-> rotation matrices; ``ego_pose`` (ego -> global) is the vehicle pose, ``calibrated_sensor``
(sensor -> ego, optical axes) the camera mount. Keyframes (2 Hz) carry the ground truth: the
pedestrians (:data:`PEDESTRIAN_CATEGORIES`) whose 3D box the devkit's ``box_in_image`` finds in
CAM_FRONT (``BoxVisibility.ANY``: all corners in front of the camera, one inside the image);
their position is the box centre's ground point in the global frame, their 2D box the
projected 3D box clipped to the image. Sweeps (the ~12 Hz frames between) have none.

A skeleton side file (:mod:`pedenv.datasets.nuscenes_skeletons`, written by
:func:`~pedenv.datasets.nuscenes_export.write_nuscenes`) adds exact skeletons: ground-truth
keypoints on keyframes, ready-made detections (confidence 1 where visible) on sweeps.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.datasets.nuscenes_skeletons import SIDE_FILE_NAME, Skeleton, read_side_file
from pedenv.errors import InputError
from pedenv.records import Camera, Detections, EgoPose, Frame, GroundTruth
from pedenv.skeleton import NUM_KEYPOINTS

#: The evaluation's pedestrian class.
PEDESTRIAN_CATEGORIES: tuple[str, ...] = ("human.pedestrian.adult", "human.pedestrian.child",
                                          "human.pedestrian.construction_worker", "human.pedestrian.police_officer")
#: The mini split's day scenes the paper evaluated.
PAPER_SCENES: tuple[str, ...] = ("scene-0061", "scene-0103", "scene-0553", "scene-0655", "scene-0757",
                                 "scene-0796", "scene-0916")
TABLES: tuple[str, ...] = ("category", "attribute", "visibility", "instance", "sensor", "calibrated_sensor",
                           "ego_pose", "log", "scene", "sample", "sample_data", "sample_annotation", "map")
CHANNEL = "CAM_FRONT"


class NuScenesDataset:
    """A nuScenes dataroot opened with the official devkit.

    data_root: the folder holding ``<version>/`` (the tables), ``samples/``, ``sweeps/``, ``maps/``.
    version: the table folder, e.g. ``v1.0-mini``.
    skeletons: a skeleton side file; defaults to ``<data_root>/pedenv_skeletons.json`` if present.
    """

    name = "nuscenes"
    default_pose_backend = "onnx"

    def __init__(self, data_root: str | Path, version: str = "v1.0-mini", skeletons: Path | None = None) -> None:
        self.root = Path(data_root)
        if not self.root.is_dir():
            raise InputError(f"nuScenes dataroot {self.root} does not exist or is not a folder")
        tables = self.root / version
        if not tables.is_dir():
            found = sorted(p.name for p in self.root.iterdir() if p.is_dir() and p.name.startswith("v"))
            raise InputError(
                f"nuScenes version folder {tables} does not exist; version folders here: {', '.join(found) or 'none'}"
            )
        missing = [t for t in TABLES if not (tables / f"{t}.json").is_file()]
        if missing:
            raise InputError(f"{tables}: missing nuScenes table(s) {', '.join(t + '.json' for t in missing)}")
        from pedenv.errors import require_extra

        require_extra("nuscenes", "nuscenes", "--dataset nuscenes")
        from nuscenes.nuscenes import NuScenes  # the optional devkit, imported only here

        try:
            self.nusc = NuScenes(version=version, dataroot=str(self.root), verbose=False)
        except (AssertionError, KeyError, ValueError, IndexError) as exc:
            raise InputError(
                f"{tables}: the nuScenes devkit cannot load these tables ({type(exc).__name__}: {exc})"
            ) from None
        self.version = version
        self._scenes = {rec["name"]: rec for rec in self.nusc.scene}
        self._instance_ids = {rec["token"]: i for i, rec in enumerate(self.nusc.instance)}
        side = Path(skeletons) if skeletons is not None else self.root / SIDE_FILE_NAME
        if skeletons is not None and not side.is_file():
            raise InputError(f"skeleton side file {side} does not exist")
        self.skeletons: dict[str, list[Skeleton]] = read_side_file(side) if side.is_file() else {}

    def scene_names(self) -> list[str]:
        """Every scene of this version, by name."""
        return sorted(self._scenes)

    def default_scenes(self) -> list[str]:
        """The paper's day scenes present here; where there are none (e.g. an export), all scenes."""
        return [s for s in PAPER_SCENES if s in self._scenes] or self.scene_names()

    def frames(self, scene: str) -> Iterator[Frame]:
        """Every CAM_FRONT image of ``scene`` in time order, keyframes with ground truth."""
        chain = self._chain(scene)
        missing = [sd["filename"] for sd in chain if not (self.root / sd["filename"]).is_file()]
        if missing:
            warnings.warn(
                f"nuScenes scene {scene}: image {self.root / missing[0]} is missing ({len(missing)} of "
                f"{len(chain)} CAM_FRONT images missing); image-based pose backends will fail on those frames",
                stacklevel=2,
            )
        for index, sd in enumerate(chain):
            try:
                with np.errstate(invalid="ignore", divide="ignore"):  # NaN is refused below, naming the record
                    frame = self._frame(sd, index, scene)
            except (InputError, ValueError, TypeError, KeyError, ZeroDivisionError) as exc:
                raise InputError(
                    f"{self.root / self.version}: scene {scene}, frame {index} (sample_data {sd['token']}, "
                    f"ego_pose, calibrated_sensor and sample_annotation tables): {exc}"
                ) from None
            yield frame

    def _chain(self, scene: str) -> list[dict]:
        if scene not in self._scenes:
            raise InputError(
                f"unknown nuScenes scene {scene!r} in {self.root / self.version}; "
                f"valid: {', '.join(sorted(self._scenes))}"
            )
        rec = self._scenes[scene]
        first = self.nusc.get("sample", rec["first_sample_token"])
        if CHANNEL not in first["data"]:
            raise InputError(f"nuScenes scene {scene}: its first sample has no {CHANNEL} image")
        nusc = self.nusc

        def in_scene(sd: dict) -> bool:
            return nusc.get("sample", sd["sample_token"])["scene_token"] == rec["token"]

        sd = nusc.get("sample_data", first["data"][CHANNEL])
        while sd["prev"] and in_scene(prev := nusc.get("sample_data", sd["prev"])):
            sd = prev
        chain = [sd]
        while sd["next"] and in_scene(nxt := nusc.get("sample_data", sd["next"])):
            sd = nxt
            chain.append(sd)
        return chain

    def _frame(self, sd: dict, index: int, scene: str) -> Frame:
        from nuscenes.utils.geometry_utils import transform_matrix
        from pyquaternion import Quaternion

        nusc = self.nusc
        pose = nusc.get("ego_pose", sd["ego_pose_token"])
        cs = nusc.get("calibrated_sensor", sd["calibrated_sensor_token"])
        ego = transform_matrix(pose["translation"], Quaternion(pose["rotation"]))  # ego -> global
        camera = Camera(np.array(cs["camera_intrinsic"], float), sd["width"], sd["height"],
                        transform_matrix(cs["translation"], Quaternion(cs["rotation"])))  # optical camera -> ego
        skeletons = self.skeletons.get(sd["token"], [])
        truth = detections = None
        if sd["is_key_frame"]:
            truth = self._ground_truth(sd, camera, pose, cs, skeletons)
        elif self.skeletons:
            skeletons = [s for s in skeletons if s.visible.any()]
            detections = Detections(np.array([s.keypoints for s in skeletons]).reshape(-1, NUM_KEYPOINTS, 2),
                                    np.array([s.visible for s in skeletons], float).reshape(-1, NUM_KEYPOINTS))
        return Frame(index=index, timestamp=sd["timestamp"] / 1e6, camera=camera, ego=EgoPose(ego[:3, 3], ego[:3, :3]),
                     detections=detections, ground_truth=truth, image_path=self.root / sd["filename"], scene=scene)

    def _ground_truth(self, sd: dict, camera: Camera, pose: dict, cs: dict, skeletons: list[Skeleton]) -> GroundTruth:
        from nuscenes.utils.geometry_utils import BoxVisibility, box_in_image, view_points
        from pyquaternion import Quaternion

        nusc = self.nusc
        size = (camera.width, camera.height)
        by_instance = {s.instance_token: s for s in skeletons}
        ids: list[int] = []
        positions: list[list[float]] = []
        boxes: list[Any] = []  # (4,) arrays from the side file or lists from the 3D box
        heights: list[float] = []
        keypoints: list[np.ndarray] = []
        visible: list[np.ndarray] = []
        for ann_token in nusc.get("sample", sd["sample_token"])["anns"]:
            ann = nusc.get("sample_annotation", ann_token)
            if ann["category_name"] not in PEDESTRIAN_CATEGORIES:
                continue
            box = nusc.get_box(ann_token)  # global frame -> ego -> camera, as the devkit's get_sample_data
            box.translate(-np.array(pose["translation"]))
            box.rotate(Quaternion(pose["rotation"]).inverse)
            box.translate(-np.array(cs["translation"]))
            box.rotate(Quaternion(cs["rotation"]).inverse)
            if not box_in_image(box, camera.intrinsics, size, vis_level=BoxVisibility.ANY):
                continue
            corners = view_points(box.corners(), camera.intrinsics, normalize=True)[:2]
            skeleton = by_instance.get(ann["instance_token"])
            if skeleton is not None and skeleton.box is not None:
                boxes.append(skeleton.box)
            else:
                boxes.append([max(corners[0].min(), 0.0), max(corners[1].min(), 0.0),
                              min(corners[0].max(), size[0]), min(corners[1].max(), size[1])])
            x, y, z = ann["translation"]
            ids.append(self._instance_ids[ann["instance_token"]])
            positions.append([x, y, z - ann["size"][2] / 2.0])
            heights.append(ann["size"][2])
            keypoints.append(skeleton.keypoints if skeleton is not None else np.zeros((NUM_KEYPOINTS, 2)))
            visible.append(skeleton.visible if skeleton is not None else np.zeros(NUM_KEYPOINTS, bool))
        with_skeletons = bool(self.skeletons)
        return GroundTruth(np.array(ids, np.int64), np.array(positions).reshape(-1, 3), np.array(boxes).reshape(-1, 4),
                           np.array(keypoints).reshape(-1, NUM_KEYPOINTS, 2) if with_skeletons else None,
                           np.array(visible, bool).reshape(-1, NUM_KEYPOINTS) if with_skeletons else None,
                           np.array(heights, float))
