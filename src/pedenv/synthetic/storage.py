"""Scenes on disk in pedenv's own ``synthetic`` format, with an exact round trip.

One folder per scene, named after the scene::

    <output_dir>/<scene name>/scene.json   metadata
    <output_dir>/<scene name>/frames.npz   flat arrays (numpy .npz, uncompressed)

``scene.json``: ``{"format": "pedenv-synthetic", "version": 1, "name", "description",
"num_frames", "image_paths": [str | null per frame], "frame_scenes": [str per frame]}``.

``frames.npz``, with T frames, P ground-truth pedestrians and D detections in all:

* per frame: ``index`` (T,) int64; ``timestamp`` (T,) float64 seconds;
  ``ego_translation`` (T, 3) and ``ego_rotation`` (T, 3, 3), vehicle -> world;
  ``intrinsics`` (T, 3, 3) pixels; ``image_size`` (T, 2) int64 width, height;
  ``cam_to_vehicle`` (T, 4, 4); ``has_gt`` and ``has_detections`` (T,) bool; optional
  ``camera_static`` (T,) bool, the camera's mount is ``static`` (absent: ``vehicle``).
* ground truth: frame ``i`` owns rows ``gt_offsets[i]:gt_offsets[i + 1]`` ((T + 1,) int64)
  of ``gt_ids`` (P,) int64, ``gt_positions`` (P, 3) world metres, ``gt_boxes`` (P, 4)
  pixels and the optional ``gt_keypoints`` (P, 17, 2), ``gt_visible`` (P, 17) bool,
  ``gt_heights`` (P,) metres, ``gt_keypoints_3d`` (P, 17, 3) world metres; for each
  optional field ``gt_has_<field>`` (T,) bool says which frames carry it (rows of the
  others are zeros).
* detections likewise: ``det_offsets`` (T + 1,), ``det_keypoints`` (D, 17, 2),
  ``det_confidences`` (D, 17), ``det_boxes`` (D, 4), ``det_scores`` (D,).

Frame images are not stored (the synthetic scenes have none); writing a frame that
holds an image array is an error.
"""

from __future__ import annotations

import json
import zipfile
import zlib
from collections.abc import Iterable
from pathlib import Path

import numpy as np
from numpy.typing import DTypeLike

from pedenv.errors import InputError
from pedenv.records import Camera, Detections, EgoPose, Frame, GroundTruth, Scene
from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.structured_text import load_json

FORMAT, VERSION = "pedenv-synthetic", 1
_OPTIONAL = {
    "keypoints": (NUM_KEYPOINTS, 2),
    "visible": (NUM_KEYPOINTS,),
    "heights": (),
    "keypoints_3d": (NUM_KEYPOINTS, 3),
}
_DETECTIONS = {"keypoints": (NUM_KEYPOINTS, 2), "confidences": (NUM_KEYPOINTS,), "boxes": (4,), "scores": ()}


def _stack(rows: list[np.ndarray], tail: tuple, dtype: DTypeLike = np.float64) -> np.ndarray:
    return np.concatenate(rows).astype(dtype) if rows else np.zeros((0, *tail), dtype)


def _offsets(counts: list[int]) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(counts, dtype=np.int64)]).astype(np.int64)


def _scene_arrays(scene: Scene) -> dict[str, np.ndarray]:
    frames = scene.frames
    for f in frames:
        if f.image is not None:
            raise InputError(f"scene {scene.name!r} frame {f.index}: the synthetic format stores no images")
    gts = [f.ground_truth if f.ground_truth is not None else GroundTruth.empty() for f in frames]
    dets = [f.detections if f.detections is not None else Detections.empty() for f in frames]
    out = {
        "index": np.array([f.index for f in frames], np.int64),
        "timestamp": np.array([f.timestamp for f in frames], np.float64),
        "ego_translation": _stack([f.ego.translation[None] for f in frames], (3,)),
        "ego_rotation": _stack([f.ego.rotation[None] for f in frames], (3, 3)),
        "intrinsics": _stack([f.camera.intrinsics[None] for f in frames], (3, 3)),
        "image_size": np.array([[f.camera.width, f.camera.height] for f in frames], np.int64).reshape(-1, 2),
        "cam_to_vehicle": _stack([f.camera.cam_to_vehicle[None] for f in frames], (4, 4)),
        "has_gt": np.array([f.ground_truth is not None for f in frames], bool),
        "has_detections": np.array([f.detections is not None for f in frames], bool),
        "gt_offsets": _offsets([len(g) for g in gts]),
        "gt_ids": _stack([g.ids for g in gts], (), np.int64),
        "gt_positions": _stack([g.positions for g in gts], (3,)),
        "gt_boxes": _stack([g.boxes for g in gts], (4,)),
        "det_offsets": _offsets([len(d) for d in dets]),
    }
    if any(f.camera.static for f in frames):  # optional: files of vehicle cameras stay as they were
        out["camera_static"] = np.array([f.camera.static for f in frames], bool)
    for name, tail in _OPTIONAL.items():
        dtype = bool if name == "visible" else np.float64
        present = [getattr(g, name) is not None for g in gts]
        out[f"gt_has_{name}"] = np.array(present, bool)
        out[f"gt_{name}"] = _stack([getattr(g, name) if p else np.zeros((len(g), *tail), dtype)
                                    for g, p in zip(gts, present)], tail, dtype)
    for name, tail in _DETECTIONS.items():
        out[f"det_{name}"] = _stack([getattr(d, name) for d in dets], tail)
    return out


def write_scenes(scenes: Iterable[Scene], output_dir: str | Path) -> None:
    """Write each scene to ``output_dir/<scene name>/`` (folders are created, files replaced)."""
    root = Path(output_dir)
    for scene in scenes:
        if not scene.name or Path(scene.name).name != scene.name or scene.name in (".", ".."):
            raise InputError(f"scene name {scene.name!r} cannot be a folder name under {root}")
        folder = root / scene.name
        folder.mkdir(parents=True, exist_ok=True)
        np.savez(folder / "frames.npz", **_scene_arrays(scene))
        meta = {"format": FORMAT, "version": VERSION, "name": scene.name, "description": scene.description,
                "num_frames": len(scene.frames),
                "image_paths": [None if f.image_path is None else str(f.image_path) for f in scene.frames],
                "frame_scenes": [f.scene for f in scene.frames]}
        (folder / "scene.json").write_text(json.dumps(meta, indent=1, allow_nan=False) + "\n")


def read_metadata(folder: str | Path) -> dict:
    """The ``scene.json`` of a scene folder, checked; InputError naming the file otherwise."""
    path = Path(folder) / "scene.json"
    if not path.is_file():
        raise InputError(f"{path}: no scene.json; not a synthetic scene folder")
    try:
        meta = load_json(path, "scene.json")
    except InputError as exc:
        raise InputError(f"{path}: cannot read JSON: {str(exc).removeprefix(f'{path}: ')}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT or meta.get("version") != VERSION:
        raise InputError(f"{path}: expected format {FORMAT!r} version {VERSION}")
    for key in ("name", "num_frames", "image_paths", "frame_scenes"):
        if key not in meta:
            raise InputError(f"{path}: missing field {key!r}")
    return meta


def read_scene(folder: str | Path) -> Scene:
    """Read the scene stored in ``folder`` by :func:`write_scenes`."""
    folder = Path(folder)
    meta = read_metadata(folder)
    path = folder / "frames.npz"
    if not path.is_file():
        raise InputError(f"{path}: missing (every scene folder holds frames.npz)")
    try:
        with np.load(path, allow_pickle=False) as data:  # object arrays (pickles) are refused, never loaded
            a = {k: data[k] for k in data.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise InputError(f"{path}: cannot read (truncated or corrupted?): {type(exc).__name__}: {exc}") from None
    needed = ["index", "timestamp", "ego_translation", "ego_rotation", "intrinsics", "image_size", "cam_to_vehicle",
              "has_gt", "has_detections", "gt_offsets", "gt_ids", "gt_positions", "gt_boxes", "det_offsets"]
    needed += [f"gt_{n}" for n in _OPTIONAL] + [f"gt_has_{n}" for n in _OPTIONAL] + [f"det_{n}" for n in _DETECTIONS]
    missing = [k for k in needed if k not in a]
    if missing:
        raise InputError(f"{path}: missing arrays {', '.join(missing)}")
    if not a["index"].shape[0] == len(meta["image_paths"]) == len(meta["frame_scenes"]) == meta["num_frames"]:
        raise InputError(f"{path}: holds {a['index'].shape[0]} frames, scene.json says {meta['num_frames']}")
    try:
        frames = tuple(_frame(a, i, meta) for i in range(a["index"].shape[0]))
        return Scene(meta["name"], frames, meta.get("description", ""))
    except (InputError, IndexError, ValueError) as exc:
        raise InputError(f"{path}: {exc}") from None


def _frame(a: dict[str, np.ndarray], i: int, meta: dict) -> Frame:
    width, height = (int(v) for v in a["image_size"][i])
    static = "camera_static" in a and bool(a["camera_static"][i])
    camera = Camera(a["intrinsics"][i], width, height, a["cam_to_vehicle"][i], "static" if static else "vehicle")
    gt = det = None
    if a["has_gt"][i]:
        rows = slice(int(a["gt_offsets"][i]), int(a["gt_offsets"][i + 1]))
        optional = {n: a[f"gt_{n}"][rows] if a[f"gt_has_{n}"][i] else None for n in _OPTIONAL}
        gt = GroundTruth(a["gt_ids"][rows], a["gt_positions"][rows], a["gt_boxes"][rows], **optional)
    if a["has_detections"][i]:
        rows = slice(int(a["det_offsets"][i]), int(a["det_offsets"][i + 1]))
        det = Detections(*(a[f"det_{n}"][rows] for n in _DETECTIONS))
    return Frame(
        int(a["index"][i]),
        float(a["timestamp"][i]),
        camera,
        EgoPose(a["ego_translation"][i], a["ego_rotation"][i]),
        detections=det,
        ground_truth=gt,
        image_path=meta["image_paths"][i],
        scene=meta["frame_scenes"][i],
    )
