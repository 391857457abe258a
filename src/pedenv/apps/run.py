"""``pedenv run``: the environment model over a user's recording, with overlays and outputs."""

from __future__ import annotations

import dataclasses
import json
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource, load_config
from pedenv.apps.pipeline import PipelineConfig, PipelineStats, run_frames
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel
from pedenv.odometry.estimator import ESTIMATED_SOURCE
from pedenv.odometry.poses_file import write_ego_poses
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.outputs.output_dir import holds_files, prepare_output_dir
from pedenv.outputs.png import write_png
from pedenv.outputs.sinks import ExtraOutputs, Sinks
from pedenv.pose.base import PoseBackend, create_pose_backend
from pedenv.pose.models import backend_options, choose_input_size
from pedenv.pose.redetect import with_redetection
from pedenv.recordings.footage import Recording
from pedenv.records import Frame
from pedenv.video_files import VideoOut, video_capture
from pedenv.visualize.overlay import draw_environment
from pedenv.visualize.plots import plot_birds_eye

if TYPE_CHECKING:
    from pedenv.recordings.bag import BagRecording
    from pedenv.state import EnvironmentState


def run_recording(source: RecordingSource, output: OutputOptions | str | Path, pose: PoseOptions | None = None, *,
                  config: Config | str | Path | None = None, method: str | None = None,
                  backend: PoseBackend | None = None, pipeline: PipelineConfig | None = None,
                  progress: Callable[[int, int], None] | None = None) -> dict:
    """Run the environment model over a recording and write everything into ``output``.

    Writes ``environment.jsonl`` (one line per frame, flushed as it goes), ``config.json``,
    ``run.json`` (pose backend and the provider that ran it, recording, frames done, speed),
    ``overlays/<index>.png`` (``output.png_compression``: stored by default, :mod:`pedenv.outputs.png`)
    or ``overlay.mp4`` (``output.video_out``) with skeletons, track ids and distances, and
    ``birds_eye.png`` of the last frame, ``birds_eye.mp4`` of every frame, and the ``output.extra``
    outputs asked for (Parquet, Rerun, MCAP; refused before the run when their extra is missing).
    Reading, the network and writing overlap (:mod:`pedenv.apps.pipeline`, ``pipeline``; its
    ``nice`` None: chosen by the outputs, :func:`_pipeline`); every output holds the frames in
    order. A bad frame stops the run with an InputError; what was computed before it stays on
    disk. ``progress(done, total)`` is called per frame written.
    ``output.folder`` must be empty or new, unless ``output.overwrite`` (then an earlier pedenv run there is
    deleted once every frame's size and ego pose are checked:
    :func:`pedenv.outputs.output_dir.prepare_output_dir`).
    A video that ends before the frame count its header gives is warned about and
    ``run.json`` says so in ``ended_early``.
    ``pose.detection`` (``onnx``): ``far`` (whole frame + tiles over the far band, the default) or
    ``fast`` (one pass fitted to the camera's aspect); None with ``pose.input_size`` None
    picks 384x640 for wide cameras, else 640 (one pass). ``pose.device`` (``onnx``): ``auto``,
    ``cpu`` or ``cuda`` (:mod:`pedenv.pose.providers`).
    ``pipeline.realtime``: frames at the recording's rate, those arriving while the model is
    busy dropped and counted (``frames_dropped``); an image folder needs its timestamps.csv or ``fps``.
    ``config``: a Config or a config.json (default ``Config()``, the fused method);
    ``method`` switches it to another position method (:func:`pedenv.localization.configure`).
    ``backend``: a pose backend already made (a worker's, kept over recordings) instead of
    the one ``pose`` describes (default: :class:`~pedenv.apps.options.PoseOptions`).
    ``source``: :class:`~pedenv.apps.options.RecordingSource` (images or video, calibration, ego
    poses, or a ROS bag). Returns the summary also saved as ``run.json``.
    """
    output, pose = OutputOptions.of(output), pose or PoseOptions()
    cfg = detection_mode(load_config(config, method), pose.backend or "onnx", pose.detection)
    pipe = _pipeline(pipeline or PipelineConfig(), output)
    extra = output.extra or ExtraOutputs()
    rec, backend, out = _open_run(source, output, pose, cfg, pipe, backend)
    model = PedestrianEnvironmentModel(cfg)
    backend = with_redetection(backend, model, cfg.redetect)  # missed tracks searched in crops (fused preset)
    summary: dict[str, Any] = {"recording": rec.name, "method": cfg.method, "pose_backend": {},
                               "frames_total": len(rec), "frames_done": 0,
                               "environment": str(out / "environment.jsonl")}
    stats, timer = PipelineStats(), _StepTimes()
    outputs = _Outputs(out, rec, output, summary, progress)
    sinks = dataclasses.replace(extra, birds_eye_video=extra.birds_eye_video or out / "birds_eye.mp4").open()
    try:
        with EnvironmentWriter(out / "environment.jsonl") as writer, sinks:
            outputs.writer, outputs.sinks = writer, sinks
            run_frames(rec.frames(), partial(_step, backend, model, timer), outputs.write, config=pipe,
                       done=outputs.done, stats=stats)
        _check_ended_early(rec, stats, summary)
    finally:
        outputs.close()
        _finish_summary(summary, out, backend, stats, timer, pipe, outputs, sinks)
        (out / "run.json").write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    return summary


def _open_run(source: RecordingSource, output: OutputOptions, pose: PoseOptions, cfg: Config,
              pipe: PipelineConfig, backend: PoseBackend | None) -> tuple[Recording | BagRecording, PoseBackend, Path]:
    """Everything checked before the output folder is touched (the extra outputs, ``--realtime``'s
    timestamps, the recording, every frame of a folder or video), then the folder prepared and
    ``config.json`` saved: (recording, pose backend, output folder)."""
    (output.extra or ExtraOutputs()).check()
    source.check_realtime(pipe.realtime)
    rec = source.load()
    backend = backend or _make_backend(pose, cfg, rec)
    if hasattr(rec, "check") and holds_files(Path(output.folder)):  # an earlier run there: every frame's size
        rec.check()  # and ego pose checked before it is touched (a bag is read once, as it runs); in a new folder
        # the frames before a bad one are run and stay on disk
    out = prepare_output_dir(output.folder, overwrite=output.overwrite, command="pedenv run")
    cfg.save(out / "config.json")
    if isinstance(rec, Recording) and rec.trajectory is not None and rec.trajectory.source == ESTIMATED_SOURCE:
        write_ego_poses(out / ESTIMATED_SOURCE, rec.trajectory)  # visual odometry's poses (pedenv.odometry)
    return rec, backend, out


#: ``pipeline.nice`` of ``pedenv run`` when none is given and its writer is lighter than the network.
WRITER_NICE = 10


def _pipeline(pipe: PipelineConfig, output: OutputOptions) -> PipelineConfig:
    """``pipe`` with ``nice`` chosen when it is None: :data:`WRITER_NICE` for the light outputs
    (overlay.mp4 or stored PNGs, about 11 ms of CPU per 1600x900 frame with the bird's-eye video
    and the JSON Lines), 0 for deflated PNGs (about 45 ms: on 2 cores more than the network's
    share, docs/speed.md)."""
    if pipe.nice is not None:
        return pipe
    light = output.video_out or output.png_compression == "none"
    return dataclasses.replace(pipe, nice=WRITER_NICE if light else 0)


def _make_backend(pose: PoseOptions, cfg: Config, rec: Recording | BagRecording) -> PoseBackend:
    """The pose backend ``pose`` describes; onnx without a detection mode, input size or model
    takes the input size fitted to the recording's camera."""
    name = pose.backend or "onnx"
    input_size: str | tuple[int, int] | None = pose.input_size
    if name == "onnx" and input_size is None and pose.model is None and pose.detection is None:
        input_size = choose_input_size(rec.camera.width, rec.camera.height)
    return create_pose_backend(name, **backend_options(
        name, pose.model, input_size, cfg.detection if pose.detection else None,
        cfg.tracking.pose_score_threshold, cfg.merge, device=pose.device))


def _check_ended_early(rec: Recording | BagRecording, stats: PipelineStats, summary: dict) -> None:
    """A video that ended before its header's frame count: warned about and noted in ``summary``."""
    if rec.video is not None and stats.taken + stats.dropped < summary["frames_total"]:
        summary["ended_early"] = (f"{rec.video}: the video ended after {stats.taken + stats.dropped} of the "
                                  f"{summary['frames_total']} frames its header announces (cut or damaged?)")
        warnings.warn(summary["ended_early"], stacklevel=3)


def _finish_summary(summary: dict, out: Path, backend: PoseBackend, stats: PipelineStats, timer: _StepTimes,
                    pipe: PipelineConfig, outputs: _Outputs, sinks: Sinks) -> None:
    """The end of ``run.json``: backend, dropped frames, speed, the bird's-eye plot and the files written."""
    summary["pose_backend"] = backend.describe() if hasattr(backend, "describe") else {"backend": backend.name}
    summary["frames_dropped"] = stats.dropped
    summary["speed"] = {**stats.to_dict(), **timer.per_frame(backend), "pipeline": dataclasses.asdict(pipe)}
    if outputs.last is not None:
        state, frame = outputs.last
        summary["birds_eye"] = str(plot_birds_eye(state, out / "birds_eye.png", frame, title=summary["recording"]))
    summary["files"] = [str(p) for p in sinks.files]


def detection_mode(cfg: Config, pose_backend: str, detection: str | None) -> Config:
    """``cfg`` with ``detection.mode`` set to a command's ``--detection`` (onnx backend), so the
    ``config.json`` of the run records the passes that ran."""
    return cfg.replace(detection={"mode": detection}) if pose_backend == "onnx" and detection else cfg


@dataclass
class _StepTimes:
    """Seconds spent in the middle stage: detection (the backend's call: network, pre- and
    post-processing, re-detection crops) and the model's update, over ``frames`` frames."""

    detection_s: float = 0.0
    model_s: float = 0.0
    frames: int = 0

    def per_frame(self, backend: PoseBackend) -> dict:
        """ms per frame of detection, model and the network alone (an onnx backend's
        ``network_s``: its session runs, counted by the backend), and network passes per frame."""
        n = max(self.frames, 1)
        onnx: Any = getattr(backend, "backend", backend)  # under the re-detection wrapper; counters read by name
        times = {"detection_ms_per_frame": 1e3 * self.detection_s / n, "model_ms_per_frame": 1e3 * self.model_s / n}
        if hasattr(onnx, "network_s"):
            times.update(network_ms_per_frame=1e3 * onnx.network_s / n, network_passes_per_frame=onnx.network_runs / n)
        return times


def _step(backend: PoseBackend, model: PedestrianEnvironmentModel, timer: _StepTimes,
          frame: Frame) -> tuple[EnvironmentState, Frame]:
    """The network and the model on one frame (the pipeline's middle stage): (state, frame)."""
    start = time.perf_counter()
    frame = dataclasses.replace(frame, detections=backend(frame))
    middle = time.perf_counter()
    state = model.update(frame)
    timer.detection_s += middle - start
    timer.model_s += time.perf_counter() - middle
    timer.frames += 1
    return state, frame


class _Outputs:
    """The writer stage: each frame's state to the JSON Lines file and the sinks, its overlay
    to a PNG or the overlay video; counts the frames written into ``summary``."""

    def __init__(self, out: Path, rec: Recording | BagRecording, output: OutputOptions, summary: dict,
                 progress: Callable[[int, int], None] | None) -> None:
        self.out, self.rec, self.summary, self.progress = out, rec, summary, progress
        self.video_out, self.png_compression = output.video_out, output.png_compression
        self.writer: EnvironmentWriter | None = None
        self.sinks: Sinks | None = None
        self.video: Any = None  # the overlay video's cv2.VideoWriter, opened at the first frame
        self.last: tuple | None = None  # (state, frame) of the last frame written

    def write(self, result: tuple[EnvironmentState, Frame]) -> None:
        state, frame = result
        assert self.writer is not None and self.sinks is not None  # set before the run
        self.writer.write(state)
        self.sinks.write(state, frame)
        if frame.image is None:
            raise InputError(f"{self.rec.name}: frame {frame.index} has no image")
        drawn = draw_environment(frame.image, state, frame)
        if self.video_out:
            if self.video is None:
                self.video = _open_video(self.out / "overlay.mp4", self.rec, drawn.shape)
            self.video.write(cv2.cvtColor(drawn, cv2.COLOR_RGB2BGR))  # 0.2 ms; drawn[..., ::-1].copy() took 8
        else:
            write_png(self.out / "overlays" / f"{frame.index:06d}.png", drawn, self.png_compression)
        self.last = (state, frame)

    def done(self, result: tuple[EnvironmentState, Frame]) -> None:  # noqa: ARG002 - the pipeline's done(result) callback
        self.summary["frames_done"] += 1
        if self.progress is not None:
            self.progress(self.summary["frames_done"], self.summary["frames_total"])

    def close(self) -> None:
        if self.video is not None:
            self.video.release()
            self.video = None


def _open_video(path: Path, rec: Recording | BagRecording, shape: tuple[int, ...]) -> VideoOut:
    stamps = np.array([t for _, t in rec.images]) if rec.images else None
    rate = rec.fps or (1.0 / float(np.median(np.diff(stamps))) if stamps is not None and len(stamps) > 1 else 10.0)
    if rec.video is not None and not rec.fps:
        with video_capture(rec.video) as cap:
            rate = cap.get(cv2.CAP_PROP_FPS) or rate
    return VideoOut(path, rate, (shape[1], shape[0]), what="overlay video")
