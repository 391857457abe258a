"""Writer of pedenv scenes as a nuScenes-format dataset that the official devkit loads.

``<output_dir>/<version>/*.json`` holds the 13 tables; CAM_FRONT images (grey JPEGs with the
ground-truth skeletons drawn) go to ``samples/CAM_FRONT/`` (keyframes) and
``sweeps/CAM_FRONT/`` (the others); ``maps/`` holds a blank map mask covering every log; the
exact skeletons go to the side file :data:`~pedenv.datasets.nuscenes_skeletons.SIDE_FILE_NAME`.

Scenes are expected at 12 Hz (CAM_FRONT's rate): every 6th frame is a keyframe (2 Hz) with
annotations, starting at the first; sweeps after the last keyframe have no next keyframe to
belong to and are left out. One scene gets one log; every frame its own ego pose.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import re
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from pedenv.datasets.nuscenes_skeletons import SIDE_FILE_NAME, skeleton_entry, write_side_file
from pedenv.errors import InputError
from pedenv.geometry import rotation_to_quaternion, rotation_z
from pedenv.records import Frame, GroundTruth, Scene
from pedenv.skeleton import COCO_BONES
from pedenv.skeleton import CocoKeypoint as K
from pedenv.validation import check_count

log = logging.getLogger(__name__)

#: Keyframe every this many CAM_FRONT frames (12 Hz -> 2 Hz).
KEYFRAME_EVERY = 6
#: The rate the exported scenes should have.
EXPECTED_RATE_HZ = 12.0
#: Footprint of an exported pedestrian box, metres: width, length (nuScenes adults average ~0.67 x 0.73).
PEDESTRIAN_WL = (0.65, 0.7)
#: Body height used when the ground truth has none, metres.
DEFAULT_HEIGHT_M = 1.75
#: Speed above which an annotation gets the attribute ``pedestrian.moving``, m/s.
MOVING_SPEED = 0.3

CATEGORIES = ("human.pedestrian.adult", "human.pedestrian.child", "human.pedestrian.construction_worker",
              "human.pedestrian.police_officer")
ATTRIBUTES = ("pedestrian.moving", "pedestrian.standing", "pedestrian.sitting_lying_down")
#: nuScenes visibility levels: token -> (level, lower bound of the visible fraction).
VISIBILITY = {"1": ("v0-40", 0.0), "2": ("v40-60", 0.4), "3": ("v60-80", 0.6), "4": ("v80-100", 0.8)}


def token(*parts: object) -> str:
    """A deterministic 32-hex-digit token for the record named by ``parts``."""
    return hashlib.md5("/".join(map(str, parts)).encode()).hexdigest()


def write_nuscenes(scenes: Iterable[Scene], output_dir: str | Path, version: str = "v1.0-mini", *,
                   jpeg_quality: int = 80) -> Path:
    """Write ``scenes`` under ``output_dir`` (the dataroot) and return the table folder.

    Scene names ``scene-NNNN`` are kept, others become ``scene-<i+1:04d>`` (the old name goes to
    the description). Ground truth on keyframes becomes ``sample_annotation`` records of category
    ``human.pedestrian.adult``: box centre = position + half the height, size ``[w, l, h]``,
    yaw from the shoulders' line where the 3D skeleton is known, one instance per (scene, id).
    """
    check_count("jpeg_quality", jpeg_quality, 1, 100)
    root = Path(output_dir)
    tables: dict[str, list[dict]] = {name: [] for name in (
        "category", "attribute", "visibility", "instance", "sensor", "calibrated_sensor", "ego_pose",
        "log", "scene", "sample", "sample_data", "sample_annotation", "map")}
    tables["category"] = [{"token": token("category", c), "name": c, "description": c} for c in CATEGORIES]
    tables["attribute"] = [{"token": token("attribute", a), "name": a, "description": a} for a in ATTRIBUTES]
    tables["visibility"] = [{"token": t, "level": lvl, "description": f"visibility of whole object is {lvl[1:]}%"}
                            for t, (lvl, _) in VISIBILITY.items()]
    sensor_token = token("sensor", "CAM_FRONT")
    tables["sensor"] = [{"token": sensor_token, "channel": "CAM_FRONT", "modality": "camera"}]
    for folder in ("samples/CAM_FRONT", "sweeps/CAM_FRONT", "maps", version):
        (root / folder).mkdir(parents=True, exist_ok=True)
    skeletons: dict[str, list[dict]] = {}
    # a generator is written scene by scene (its images at once, only table rows kept)
    names = _scene_names(scenes) if isinstance(scenes, Sequence) else (f"scene-{i + 1:04d}" for i in itertools.count())
    for scene, name in zip(scenes, names):
        _write_scene(scene, name, root, tables, skeletons, sensor_token, jpeg_quality)
    map_file = "maps/pedenv_blank.png"
    (root / map_file).write_bytes(cv2.imencode(".png", np.zeros((64, 64), np.uint8))[1].tobytes())
    tables["map"] = [{"token": token("map"), "category": "semantic_prior", "filename": map_file,
                      "log_tokens": [r["token"] for r in tables["log"]]}]
    for name, records in tables.items():
        (root / version / f"{name}.json").write_text(json.dumps(records, indent=0, allow_nan=False))
    write_side_file(root / SIDE_FILE_NAME, skeletons)
    return root / version


def _scene_names(scenes: Sequence[Scene]) -> list[str]:
    names = [s.name if re.fullmatch(r"scene-\d{4}", s.name) else f"scene-{i + 1:04d}" for i, s in enumerate(scenes)]
    if len(set(names)) != len(names):
        raise InputError(f"scene names must be unique once written as scene-NNNN, got {[s.name for s in scenes]}")
    return names


def _exported_frames(scene: Scene) -> list[Frame]:
    """The frames of ``scene`` up to its last keyframe (a warning when it does not run at 12 Hz)."""
    frames = scene.frames
    if not frames:
        raise InputError(f"scene {scene.name!r} has no frames to write")
    if len(frames) > 1:
        rate = (len(frames) - 1) / (frames[-1].timestamp - frames[0].timestamp)
        if abs(rate - EXPECTED_RATE_HZ) > 0.1 * EXPECTED_RATE_HZ:
            warnings.warn(f"scene {scene.name!r} runs at {rate:.1f} Hz, not {EXPECTED_RATE_HZ:g} Hz: its keyframes "
                          f"(every {KEYFRAME_EVERY}th frame) will not be 2 Hz", stacklevel=4)
    n = (len(frames) - 1) // KEYFRAME_EVERY * KEYFRAME_EVERY + 1
    if n < len(frames):
        log.info(
            "scene %s: the last %d frame(s) follow the last keyframe and are not exported", scene.name, len(frames) - n
        )
    return list(frames[:n])


def _write_scene(scene: Scene, name: str, root: Path, tables: dict, skeletons: dict, sensor_token: str,
                 jpeg_quality: int) -> None:
    frames = _exported_frames(scene)
    n = len(frames)
    scene_token, log_token = token("scene", name), token("log", name)
    tables["log"].append({"token": log_token, "logfile": f"pedenv-{name}", "vehicle": "pedenv",
                          "date_captured": "2024-01-01", "location": "pedenv-synthetic"})
    stamps = [int(round(f.timestamp * 1e6)) for f in frames]
    keys = list(range(0, n, KEYFRAME_EVERY))
    sample_tokens = {i: token("sample", name, i) for i in keys}
    for j, i in enumerate(keys):
        tables["sample"].append({"token": sample_tokens[i], "timestamp": stamps[i], "scene_token": scene_token,
                                 "prev": sample_tokens[keys[j - 1]] if j else "",
                                 "next": sample_tokens[keys[j + 1]] if j + 1 < len(keys) else ""})
    tables["scene"].append({"token": scene_token, "log_token": log_token, "nbr_samples": len(keys), "name": name,
                            "description": scene.description or scene.name,
                            "first_sample_token": sample_tokens[keys[0]], "last_sample_token": sample_tokens[keys[-1]]})
    sd_tokens = [token("sample_data", name, i) for i in range(n)]
    calibrations: dict[bytes, str] = {}
    anns = _Annotations()
    for i, frame in enumerate(frames):
        is_key = i % KEYFRAME_EVERY == 0
        cs_token = _calibration(frame, name, tables, calibrations, sensor_token)
        ego_token = token("ego_pose", name, i)
        tables["ego_pose"].append({"token": ego_token, "timestamp": stamps[i],
                                   "translation": frame.ego.translation.tolist(),
                                   "rotation": rotation_to_quaternion(frame.ego.rotation).tolist()})
        filename = f"{'samples' if is_key else 'sweeps'}/CAM_FRONT/{name}__CAM_FRONT__{stamps[i]}.jpg"
        _write_image(frame, root / filename, jpeg_quality)
        tables["sample_data"].append({
            "token": sd_tokens[i], "sample_token": sample_tokens[-(-i // KEYFRAME_EVERY) * KEYFRAME_EVERY],
            "ego_pose_token": ego_token, "calibrated_sensor_token": cs_token, "timestamp": stamps[i],
            "fileformat": "jpg", "is_key_frame": is_key, "height": frame.camera.height, "width": frame.camera.width,
            "filename": filename, "prev": sd_tokens[i - 1] if i else "", "next": sd_tokens[i + 1] if i + 1 < n else ""})
        _add_ground_truth(frame, name, i, stamps[i], sample_tokens[i] if is_key else None, sd_tokens[i],
                          skeletons, anns)
    _link_instances(anns.by_instance, tables)
    for ann in anns.ordered:
        del ann["_time"]
    tables["sample_annotation"].extend(anns.ordered)


@dataclass
class _Annotations:
    """A scene's keyframe annotations: frame by frame in ground-truth order (the devkit lists a
    sample's annotations in table order), and the same records per instance token."""

    ordered: list[dict] = field(default_factory=list)
    by_instance: dict[str, list[dict]] = field(default_factory=dict)


def _add_ground_truth(frame: Frame, name: str, index: int, stamp: int, sample_token: str | None, sd_token: str,
                      skeletons: dict, anns: _Annotations) -> None:
    """Frame ``index`` (``stamp`` us) of scene ``name``: its skeletons into ``skeletons`` (the side
    file's, by sample-data token) and, on a keyframe (``sample_token`` given), its annotations into ``anns``."""
    gt = frame.ground_truth
    if gt is None:
        return
    if gt.keypoints is not None and gt.visible is not None:
        skeletons[sd_token] = [skeleton_entry(_instance_key(name, gt.ids[m], index, m), gt.keypoints[m],
                                              gt.visible[m], gt.boxes[m]) for m in range(len(gt))]
    if sample_token is not None:
        for m in range(len(gt)):
            key = _instance_key(name, gt.ids[m], index, m)
            anns.ordered.append(_annotation(gt, m, key, sample_token, stamp))
            anns.by_instance.setdefault(key, []).append(anns.ordered[-1])


def _instance_key(scene: str, pid: int, frame: int, m: int) -> str:
    """The instance token of ground-truth person ``m`` of a frame (ids of -1 are one-off instances)."""
    return token("instance", scene, int(pid)) if pid >= 0 else token("instance", scene, "anonymous", frame, m)


def _calibration(frame: Frame, scene: str, tables: dict, known: dict, sensor_token: str) -> str:
    cam = frame.camera
    key = cam.intrinsics.tobytes() + cam.cam_to_vehicle.tobytes() + bytes(f"{cam.width}x{cam.height}", "ascii")
    if key not in known:
        known[key] = token("calibrated_sensor", scene, len(known))
        tables["calibrated_sensor"].append({
            "token": known[key], "sensor_token": sensor_token, "translation": cam.cam_to_vehicle[:3, 3].tolist(),
            "rotation": rotation_to_quaternion(cam.cam_to_vehicle[:3, :3]).tolist(),
            "camera_intrinsic": cam.intrinsics.tolist()})
    return known[key]


def _annotation(gt: GroundTruth, m: int, instance_token: str, sample_token: str, stamp: int) -> dict:
    height = float(gt.heights[m]) if gt.heights is not None else DEFAULT_HEIGHT_M
    yaw = 0.0
    if gt.keypoints_3d is not None:
        left = gt.keypoints_3d[m, K.LEFT_SHOULDER] - gt.keypoints_3d[m, K.RIGHT_SHOULDER]
        yaw = float(np.arctan2(-left[0], left[1]))  # facing = left x up
    seen = float(gt.visible[m].mean()) if gt.keypoints is not None and gt.visible is not None else 1.0
    visibility = max(t for t, (_, low) in VISIBILITY.items() if seen >= low)
    return {"token": token("sample_annotation", instance_token, stamp), "sample_token": sample_token,
            "instance_token": instance_token, "visibility_token": visibility, "attribute_tokens": [],
            "translation": (gt.positions[m] + [0.0, 0.0, height / 2.0]).tolist(),
            "size": [PEDESTRIAN_WL[0], PEDESTRIAN_WL[1], height],
            "rotation": rotation_to_quaternion(rotation_z(yaw)).tolist(),
            "prev": "", "next": "", "num_lidar_pts": 5, "num_radar_pts": 0, "_time": stamp / 1e6}


def _link_instances(annotations: dict[str, list[dict]], tables: dict) -> None:
    """Chain each instance's annotations through prev/next, set attributes from speed, add instances."""
    category = token("category", CATEGORIES[0])
    for inst, anns in annotations.items():
        for j, ann in enumerate(anns):
            ann["prev"] = anns[j - 1]["token"] if j else ""
            ann["next"] = anns[j + 1]["token"] if j + 1 < len(anns) else ""
            a, b = anns[max(j - 1, 0)], anns[min(j + 1, len(anns) - 1)]
            dt = b["_time"] - a["_time"]
            speed = np.hypot(*np.subtract(b["translation"][:2], a["translation"][:2])) / dt if dt > 0 else 0.0
            ann["attribute_tokens"] = [token("attribute", ATTRIBUTES[0 if speed > MOVING_SPEED else 1])]
        tables["instance"].append(
            {
                "token": inst,
                "category_token": category,
                "nbr_annotations": len(anns),
                "first_annotation_token": anns[0]["token"],
                "last_annotation_token": anns[-1]["token"],
            }
        )


def _write_image(frame: Frame, path: Path, quality: int) -> None:
    """A grey image of the camera's size with the ground-truth skeletons drawn in white."""
    image = np.full((frame.camera.height, frame.camera.width, 3), 96, np.uint8)
    gt = frame.ground_truth
    if gt is not None and gt.keypoints is not None and gt.visible is not None:
        for kp, vis in zip(np.round(gt.keypoints).astype(int), gt.visible):
            for a, b in COCO_BONES:
                if vis[a] and vis[b]:
                    cv2.line(image, tuple(map(int, kp[a])), tuple(map(int, kp[b])), (255, 255, 255), 2)
    ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, quality])  # written by Python: any name
    if not ok:
        raise OSError(f"could not encode image {path}")
    path.write_bytes(data.tobytes())
