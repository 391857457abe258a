"""``pedenv run --manifest``: many recordings, one task each, serially or on Ray.

    summary = run_manifest("drives.csv", "out", executor=ExecutorOptions("ray", workers=2))

Each row of the manifest (:mod:`pedenv.recordings.manifest`) is one
:func:`~pedenv.apps.run.run_recording` into ``<output>/<name>/``, as ``pedenv run`` writes
it. The pose network is loaded once per worker process and kept for its later
recordings. ``<output>/summary.json`` lists every recording in manifest order with its
status (``done``, ``failed`` with the error, ``resumed``, or ``interrupted`` for the
recordings not finished when Ctrl-C stopped the run: ``summary.json`` is written then too,
``"interrupted": true``), frames and folder. A recording
that fails stops alone: the others finish, and what it wrote before the failure stays.
``resume`` keeps the recordings an earlier run completed (their ``run.json`` counts every
frame) and runs the others again.

On a Ray cluster every machine must see the manifest's files and the output folder under
the same paths (a shared file system): the workers read and write them directly.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console

from pedenv.apps.executors import TaskContext, create_executor
from pedenv.apps.options import ExecutorOptions, OutputOptions, PoseOptions, RecordingSource, load_config
from pedenv.apps.output_safety import check_outputs, list_files, prepare_folder
from pedenv.apps.progress import FrameCounter, progress_bar
from pedenv.apps.run import detection_mode, run_recording
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.recordings.manifest import SUMMARY, ManifestRow, read_manifest
from pedenv.structured_text import load_json

if TYPE_CHECKING:
    from pedenv.pose.base import PoseBackend


def run_manifest(manifest: str | Path, output: OutputOptions | str | Path, pose: PoseOptions | None = None, *,
                 executor: ExecutorOptions | None = None, config: Config | str | Path | None = None,
                 method: str | None = None, progress: bool = False) -> dict:
    """Run every recording of ``manifest`` into ``output.folder``; returns the summary saved as ``summary.json``.

    ``pose``, ``config`` and ``output.video_out`` are those of :func:`~pedenv.apps.run.run_recording`,
    for every recording (``method``: as ``pedenv run --method``, applied to ``config``);
    ``output.overwrite`` empties an earlier run's folder, ``executor.resume`` continues it.
    ``summary["failed"]`` counts the recordings that failed.
    """
    from pedenv.apps.distributed import prepare_resume_dir

    output, pose, executor = OutputOptions.of(output), pose or PoseOptions(), executor or ExecutorOptions()
    rows = read_manifest(manifest)
    cfg = load_config(config, method)
    inputs = [("--manifest", manifest), ("--config", config if isinstance(config, (str, Path)) else None)]
    inputs += [(f"manifest row {r.row} {flag}", path) for r in rows for flag, path in (
        ("images", r.images), ("video", r.video), ("calibration", r.calibration), ("ego_poses", r.ego_poses))]
    check_outputs(output.folder, inputs, None)  # no recording's file in the folder (--overwrite empties it)
    out = prepare_resume_dir(Path(output.folder)) if executor.resume else prepare_folder(
        output.folder, [], None, overwrite=output.overwrite, command="pedenv run --manifest")
    entries: dict[str, dict[str, Any]] = {}
    if executor.resume:
        entries = {r.name: {**_complete(out / r.name), "status": "resumed"} for r in rows if _complete(out / r.name)}
    todo = [r for r in rows if r.name not in entries]
    options = {"pose": pose, "video_out": output.video_out, "config": cfg}
    interrupted = False
    try:
        with create_executor(executor.name, address=executor.address, workers=executor.workers,
                             object_store_memory=executor.object_store_memory) as ex, \
                progress_bar(Console(stderr=True, emoji=False, markup=False), enabled=progress) as bar:
            counter = FrameCounter(bar, len(rows), already=len(entries), noun="recordings")
            shared = {"options": options, "output": str(out)}
            for row, value, error in ex.run(_recording_task, todo, shared=shared, on_progress=counter.update):
                if error is None:
                    entries[row.name] = {**value, "status": "done"}
                else:
                    entries[row.name] = {**_complete(out / row.name, partial=True), "status": "failed",
                                         "error": f"{type(error).__name__}: {error}"}
                counter.finish(row, failed=error is not None)
    except KeyboardInterrupt:
        interrupted = True
        raise
    finally:  # also after Ctrl-C: the recordings finished so far are listed
        summary = _write_summary(manifest, out, executor.name, rows, entries, interrupted)
        list_files(out, "pedenv run --manifest")  # what a later --overwrite may delete
    return summary


def _write_summary(manifest: str | Path, out: Path, executor: str, rows: list[ManifestRow], entries: dict,
                   interrupted: bool) -> dict:
    """``out/summary.json``: every row in manifest order; a row without an entry is ``interrupted``
    (Ctrl-C) or ``not run`` (the executor failed)."""
    missing = "interrupted" if interrupted else "not run"
    recordings = [{"name": r.name, "row": r.row, "output": str(out / r.name),
                   **entries.get(r.name, {**_complete(out / r.name, partial=True), "status": missing})}
                  for r in rows]
    summary = {"manifest": str(manifest), "output": str(out), "executor": executor, "recordings": recordings,
               "failed": sum(e["status"] == "failed" for e in recordings), "interrupted": interrupted}
    tmp = out / f".{SUMMARY}.tmp"
    tmp.write_text(json.dumps(summary, indent=2, allow_nan=False, default=str) + "\n")
    tmp.replace(out / SUMMARY)  # whole or not at all
    return summary


def _recording_task(row: ManifestRow, context: TaskContext) -> dict:
    """One recording on a worker, with the worker's pose backend (made at its first recording)."""
    o = context.shared["options"]
    pose: PoseOptions = o["pose"]
    backend = None
    if pose.backend != "onnx" or pose.detection is not None or pose.input_size is not None:
        # else run_recording picks the input size from each recording's camera
        backend = context.cached(("pose", pose.backend, str(pose.model), pose.input_size, pose.detection),
                                 lambda: _make_backend(pose, o["config"]))
    source = RecordingSource(calibration=row.calibration, ego_poses=row.ego_poses, images=row.images,
                             video=row.video, fps=row.fps, start_time=row.start_time)
    output = OutputOptions(Path(context.shared["output"]) / row.name, overwrite=True, video_out=o["video_out"])
    return run_recording(source, output, pose, config=o["config"], backend=backend, progress=context.report)


def _make_backend(pose: PoseOptions, config: Config) -> PoseBackend:
    from pedenv.detection import backend_options, create_detector

    name = pose.backend or "onnx"
    cfg = detection_mode(config, name, pose.detection)
    return create_detector(name, **backend_options(
        name, pose.model, pose.input_size, cfg.detection if pose.detection else None,
        cfg.tracking.pose_score_threshold, redetect=cfg.redetect))


def _complete(folder: Path, partial: bool = False) -> dict:
    """The ``run.json`` of a recording's folder when it counts every frame (or, ``partial``, whatever it holds)."""
    try:
        summary = load_json(folder / "run.json", "run.json")
    except InputError:
        return {}
    if partial or summary.get("frames_done") == summary.get("frames_total") or "ended_early" in summary:
        return summary
    return {}
