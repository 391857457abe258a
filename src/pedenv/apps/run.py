"""``pedenv run``: the environment model over a user's recording, with overlays and outputs."""

from __future__ import annotations

import dataclasses
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.images import write_image
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.outputs.output_dir import prepare_output_dir
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.pose.base import PoseBackend, create_pose_backend
from pedenv.pose.models import backend_options, choose_input_size
from pedenv.pose.redetect import with_redetection
from pedenv.recordings.footage import Recording, load_recording
from pedenv.visualize.overlay import draw_environment
from pedenv.visualize.plots import plot_birds_eye


def run_recording(*, calibration, ego_poses, output, images=None, video=None, fps=None, start_time=None, static=False,
                  pose_backend: str = "onnx", pose_model=None, pose_input_size=None, config=None,
                  video_out: bool = False, overwrite: bool = False, progress=None,
                  detection: str | None = "far", extra_outputs: ExtraOutputs | None = None,
                  method: str | None = None, backend: PoseBackend | None = None) -> dict:
    """Run the environment model over a recording and write everything into ``output``.

    Writes ``environment.jsonl`` (one line per frame, flushed as it goes), ``config.json``,
    ``run.json`` (pose backend, recording, frames done), ``overlays/<index>.png`` or
    ``overlay.mp4`` (``video_out``) with skeletons, track ids and distances, and
    ``birds_eye.png`` of the last frame, ``birds_eye.mp4`` of every frame, and the
    ``extra_outputs`` asked for (Parquet, Rerun, MCAP; refused before the run when their extra
    is missing). A bad frame stops the run with an InputError; what was computed before it
    stays on disk. ``progress(done, total)`` is called per frame.
    ``output`` must be empty or new, unless ``overwrite`` (then an earlier pedenv run there is
    deleted once the inputs are checked: :func:`pedenv.outputs.output_dir.prepare_output_dir`).
    A video that ends before the frame count its header gives is warned about and
    ``run.json`` says so in ``ended_early``.
    ``detection`` (``onnx``): ``far`` (whole frame + tiles over the far band, the default) or
    ``fast`` (one pass fitted to the camera's aspect); None with ``pose_input_size`` None
    picks 384x640 for wide cameras, else 640 (one pass).
    ``config``: a Config or a config.json (default ``Config()``, the fused method);
    ``method`` switches it to another position method (:func:`pedenv.localization.configure`).
    ``backend``: a pose backend already made (a worker's, kept over recordings) instead of
    the one ``pose_backend``, ``pose_model``, ``pose_input_size`` and ``detection`` describe.
    ``static``: the camera is fixed to the ground (``mount: static``, whatever the calibration
    says); ``ego_poses`` may then be None (:func:`pedenv.recordings.footage.load_recording`).
    Returns the summary also saved as ``run.json``.
    """
    cfg = config if isinstance(config, Config) else (Config.load(config) if config else Config())
    cfg = configure(cfg, method) if method else cfg
    extra = extra_outputs or ExtraOutputs()
    extra.check()
    rec = load_recording(calibration=calibration, ego_poses=ego_poses, images=images, video=video, fps=fps,
                         start_time=start_time, static=static)
    if pose_backend == "onnx" and pose_input_size is None and pose_model is None and detection is None:
        pose_input_size = choose_input_size(rec.camera.width, rec.camera.height)
    if backend is None:
        backend = create_pose_backend(pose_backend, **backend_options(
            pose_backend, pose_model, pose_input_size, detection, cfg.tracking.pose_score_threshold))
    out = prepare_output_dir(output, overwrite=overwrite, command="pedenv run")
    cfg.save(out / "config.json")
    model = PedestrianEnvironmentModel(cfg)
    backend = with_redetection(backend, model, cfg.redetect)  # missed tracks searched in crops (fused preset)
    summary: dict[str, Any] = {"recording": rec.name, "method": cfg.method, "pose_backend": {},
                               "frames_total": len(rec), "frames_done": 0,
                               "environment": str(out / "environment.jsonl")}
    writer_video, last = None, None
    sinks = dataclasses.replace(extra, birds_eye_video=extra.birds_eye_video or out / "birds_eye.mp4").open()
    try:
        with EnvironmentWriter(out / "environment.jsonl") as writer, sinks:
            for frame in rec.frames():
                frame = dataclasses.replace(frame, detections=backend(frame))
                state = model.update(frame)
                writer.write(state)
                sinks.write(state, frame)
                if frame.image is None:
                    raise InputError(f"{rec.name}: frame {frame.index} has no image")
                drawn = draw_environment(frame.image, state)
                if video_out:
                    writer_video = writer_video or _open_video(out / "overlay.mp4", rec, drawn.shape)
                    writer_video.write(drawn[..., ::-1].copy())
                else:
                    write_image(out / "overlays" / f"{frame.index:06d}.png", drawn)
                last = (state, frame)
                summary["frames_done"] += 1
                if progress is not None:
                    progress(summary["frames_done"], summary["frames_total"])
        if rec.video is not None and summary["frames_done"] < summary["frames_total"]:
            summary["ended_early"] = (f"{rec.video}: the video ended after {summary['frames_done']} of the "
                                      f"{summary['frames_total']} frames its header announces (cut or damaged?)")
            warnings.warn(summary["ended_early"], stacklevel=2)
    finally:
        if writer_video is not None:
            writer_video.release()
        summary["pose_backend"] = backend.describe() if hasattr(backend, "describe") else {"backend": backend.name}
        if last is not None:
            summary["birds_eye"] = str(plot_birds_eye(last[0], out / "birds_eye.png", last[1], title=rec.name))
        summary["files"] = [str(p) for p in sinks.files]
        (out / "run.json").write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    return summary


def _open_video(path: Path, rec: Recording, shape):
    import cv2

    stamps = np.array([t for _, t in rec.images]) if rec.images else None
    rate = rec.fps or (1.0 / float(np.median(np.diff(stamps))) if stamps is not None and len(stamps) > 1 else 10.0)
    if rec.video is not None and not rec.fps:
        cap = cv2.VideoCapture(str(rec.video))
        rate = cap.get(cv2.CAP_PROP_FPS) or rate
        cap.release()
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"mp4v"), rate, (shape[1], shape[0]))
    if not writer.isOpened():
        raise InputError(f"{path}: cannot write the overlay video")
    return writer
