"""A finished scene's checkpoint as data: one ``.npz`` of plain arrays, read without pickle.

    save_checkpoint(path, result, run)       # atomically: it marks the scene complete
    result = load_checkpoint(path, name, run)

The file holds a :class:`~pedenv.apps.scene_result.SceneResult` (its ``lines`` are in the
scene's ``environment.jsonl``) as numeric and string arrays and one JSON text (``meta``):
the scene, frame count, stage timings, which run wrote it (``run``: dataset, pose backend
and the whole config) and the shapes of the busiest frame. It is read with
``np.load(allow_pickle=False)`` and rebuilt through the validating records, so a forged
file can give a clear error, never run code. The tracking accumulators are kept as their
motmetrics event tables (they score to the same digits); the busiest frame keeps no image.

A checkpoint written by another run (method, config, pose backend or dataset) is refused
with a line naming the scene and the first differences: resuming merges it into this run.
"""

from __future__ import annotations

import dataclasses
import io
import json
import os
import zipfile
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from pedenv.apps.scene_result import SceneResult
from pedenv.errors import InputError
from pedenv.evaluation.behaviour import samples_from_arrays, samples_to_arrays
from pedenv.evaluation.metrics import ErrorSamples
from pedenv.records import Camera, Detections, EgoPose, Frame, GroundTruth
from pedenv.stage_timer import StageTimer
from pedenv.state import Behaviour, EnvironmentState, Pedestrians

if TYPE_CHECKING:
    import pandas as pd

#: What ``meta["format"]`` says, and the version of the layout below.
FORMAT, VERSION = "pedenv-scene-checkpoint", 1
SAMPLE_FIELDS = ("abs_err", "rel_err", "distance", "mahalanobis")
EVENT_COLUMNS = ("FrameId", "Event", "Type", "OId", "HId", "D")
PEDESTRIAN_FIELDS = ("track_ids", "ages", "positions", "velocities", "covariances", "keypoints", "confidences",
                     "boxes", "keypoints_3d", "distances", "sources")
DETECTION_FIELDS = ("keypoints", "confidences", "boxes", "scores")
TRUTH_FIELDS = ("ids", "positions", "boxes", "keypoints", "visible", "heights", "keypoints_3d")


def run_identity(dataset: str, pose_backend: str, config: dict) -> dict:
    """What a checkpoint must share with the run that resumes it, as JSON gives it back."""
    return json.loads(json.dumps({"dataset": dataset, "pose_backend": pose_backend, "config": config}))


def save_checkpoint(path: Path, result: SceneResult, run: dict) -> None:
    """Write ``result`` (without its lines) to ``path`` atomically (a temporary file, then a rename)."""
    arrays: dict[str, np.ndarray] = {}
    for k, v in result.samples.arrays().items():
        arrays[f"samples.{k}"] = v
    for i, acc in enumerate(result.tracking.values()):
        events = acc.events if hasattr(acc, "events") else acc  # a MOTAccumulator, or its table (resumed)
        arrays[f"tracking.{i}.FrameId"] = events.index.get_level_values("FrameId").to_numpy(np.int64)
        arrays[f"tracking.{i}.Event"] = events.index.get_level_values("Event").to_numpy(np.int64)
        arrays[f"tracking.{i}.Type"] = events["Type"].astype(str).to_numpy(str)
        for col in ("OId", "HId", "D"):
            arrays[f"tracking.{i}.{col}"] = events[col].to_numpy(np.float64)
    if result.behaviour is not None:
        arrays.update(samples_to_arrays(result.behaviour))
    busiest = None
    if result.busiest is not None:
        busiest = _busiest_arrays(*result.busiest, arrays)
    meta = {"format": FORMAT, "version": VERSION, "scene": result.name, "frames": result.frames,
            "busiest_count": result.busiest_count, "timer": vars(result.timer), "run": run,
            "tracking": list(result.tracking), "busiest": busiest}
    arrays["meta"] = np.array(json.dumps(meta, allow_nan=False))
    buffer = io.BytesIO()  # numpy's savez leaves its ZipFile open when interrupted (Ctrl-C): never on a closed file
    np.savez(buffer, **arrays)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(buffer.getbuffer())
    os.replace(tmp, path)


def _busiest_arrays(state: EnvironmentState, frame: Frame, arrays: dict) -> dict:
    """Put the busiest frame's arrays into ``arrays``; returns its scalars for the meta."""
    for name in PEDESTRIAN_FIELDS:
        arrays[f"state.{name}"] = np.asarray(getattr(state.pedestrians, name))
    arrays["state.ego_translation"], arrays["state.ego_rotation"] = state.ego.translation, state.ego.rotation
    behaviour = state.pedestrians.behaviour
    scalars = None
    if behaviour is not None:  # the cues' arrays, and their per-frame numbers in the meta
        scalars = {}
        for f in dataclasses.fields(behaviour):
            value = getattr(behaviour, f.name)
            if isinstance(value, np.ndarray):
                arrays[f"behaviour.{f.name}"] = value
            else:
                scalars[f.name] = float(value)
    cam = frame.camera
    arrays["frame.intrinsics"], arrays["frame.cam_to_vehicle"] = cam.intrinsics, cam.cam_to_vehicle
    arrays["frame.ego_translation"], arrays["frame.ego_rotation"] = frame.ego.translation, frame.ego.rotation
    for prefix, record, fields in (("detections", frame.detections, DETECTION_FIELDS),
                                   ("truth", frame.ground_truth, TRUTH_FIELDS)):
        for name in fields if record is not None else ():
            if getattr(record, name) is not None:
                arrays[f"{prefix}.{name}"] = getattr(record, name)
    return {"state_index": state.frame_index, "state_timestamp": state.timestamp, "state_scene": state.scene,
            "index": frame.index, "timestamp": frame.timestamp, "width": cam.width, "height": cam.height,
            "scene": frame.scene, "image_path": None if frame.image_path is None else str(frame.image_path),
            "detections": frame.detections is not None, "truth": frame.ground_truth is not None,
            "behaviour": scalars}


def load_checkpoint(path: Path, name: str, run: dict) -> SceneResult:
    """The checkpoint of scene ``name`` at ``path``, written by a run like ``run``
    (:func:`run_identity`); InputError naming the file and the scene otherwise."""
    hint = f"delete {path.parent} to run scene {name} again"
    try:
        with np.load(path, allow_pickle=False) as npz:
            arrays = {k: npz[k] for k in npz.files}
        meta = json.loads(str(arrays.pop("meta")))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise InputError(f"{path}: not a pedenv scene checkpoint ({type(exc).__name__}: {exc}); {hint}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT or meta.get("version") != VERSION:
        raise InputError(f"{path}: not a pedenv scene checkpoint of version {VERSION}; {hint}")
    if meta.get("scene") != name:
        raise InputError(f"{path}: holds scene {meta.get('scene')!r}, not {name!r}; {hint}")
    if meta.get("run") != run:
        diff = _differences(meta.get("run"), run)
        raise InputError(f"{path}: scene {name} was checkpointed by another run ({diff}); "
                         f"resume with the same settings, or {hint} (--overwrite starts afresh)")
    try:
        return _rebuild(meta, arrays)
    except (InputError, KeyError, TypeError, ValueError, IndexError) as exc:
        raise InputError(f"{path}: a damaged checkpoint of scene {name} ({type(exc).__name__}: {exc}); "
                         f"{hint}") from None


def _differences(saved: object, current: dict, limit: int = 3) -> str:
    """The first ``limit`` differing settings: ``config.method paper (this run: fused)``."""
    out: list[str] = []

    def walk(a: object, b: object, where: str) -> None:
        if isinstance(a, dict) and isinstance(b, dict):
            for key in list(b) + [k for k in a if k not in b]:
                walk(a.get(key), b.get(key), f"{where}.{key}" if where else key)
        elif a != b:
            out.append(f"{where} {json.dumps(a)} (this run: {json.dumps(b)})")

    walk(saved, current, "")
    return ", ".join(out[:limit]) + (f" and {len(out) - limit} more" if len(out) > limit else "")


def _rebuild(meta: dict, arrays: dict[str, np.ndarray]) -> SceneResult:
    samples = ErrorSamples()
    samples.add(*(np.asarray(arrays[f"samples.{k}"], np.float64) for k in SAMPLE_FIELDS))
    tracking = {str(key): _events(arrays, i) for i, key in enumerate(meta["tracking"])}
    timer = StageTimer(**{k: meta["timer"][k] for k in ("tracking_s", "frames", "position_s", "pedestrians")})
    busiest = None if meta["busiest"] is None else _busiest(meta["busiest"], arrays)
    return SceneResult(meta["scene"], samples, tracking, timer, int(meta["frames"]), busiest,
                       int(meta["busiest_count"]), behaviour=samples_from_arrays(arrays))


def _events(arrays: dict[str, np.ndarray], i: int) -> pd.DataFrame:
    """The motmetrics event table of accumulator ``i`` (what ``MOTAccumulator.events`` gives)."""
    import motmetrics  # imported here: only evaluation needs it

    cols = {c: arrays[f"tracking.{i}.{c}"] for c in EVENT_COLUMNS}
    return motmetrics.MOTAccumulator.new_event_dataframe_with_data(
        {"FrameId": cols["FrameId"].astype(np.int64).tolist(), "Event": cols["Event"].astype(np.int64).tolist()},
        {"Type": cols["Type"].astype(str).tolist(), **{c: cols[c].astype(np.float64) for c in ("OId", "HId", "D")}})


def _busiest(b: dict, arrays: dict[str, np.ndarray]) -> tuple[EnvironmentState, Frame]:
    behaviour = None
    if b.get("behaviour") is not None:
        cues: dict = {k[len("behaviour."):]: v for k, v in arrays.items() if k.startswith("behaviour.")}
        cues.update({k: float(v) for k, v in b["behaviour"].items()})
        behaviour = Behaviour(**cues)
    columns: dict = {n: arrays[f"state.{n}"] for n in PEDESTRIAN_FIELDS}
    peds = Pedestrians(**columns, behaviour=behaviour)
    state = EnvironmentState(int(b["state_index"]), float(b["state_timestamp"]),
                             EgoPose(arrays["state.ego_translation"], arrays["state.ego_rotation"]), peds,
                             str(b["state_scene"]))
    camera = Camera(arrays["frame.intrinsics"], int(b["width"]), int(b["height"]), arrays["frame.cam_to_vehicle"])
    det = Detections(*(arrays[f"detections.{n}"] for n in DETECTION_FIELDS)) if b["detections"] else None
    truth = GroundTruth(**{n: arrays[f"truth.{n}"] for n in TRUTH_FIELDS if f"truth.{n}" in arrays}) \
        if b["truth"] else None
    frame = Frame(int(b["index"]), float(b["timestamp"]), camera,
                  EgoPose(arrays["frame.ego_translation"], arrays["frame.ego_rotation"]), det, truth,
                  image_path=None if b["image_path"] is None else Path(b["image_path"]), scene=str(b["scene"]))
    return state, frame
