"""``pedenv run``: the environment model over a user's recording, with overlays and outputs."""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Callable, Iterable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from pedenv.apps.calibrate import SelfCalibration, estimate_for_source, needs_estimate
from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource, load_config
from pedenv.apps.output_safety import DiskGuard, RunFolder, open_run_folder
from pedenv.apps.pipeline import PipelineConfig, PipelineStats, decoded_ahead, run_frames
from pedenv.apps.run_outputs import (
    OverlayWriter,
    check_run_paths,
    finish_run,
    in_work_folder,
    live_address,
    outside,
)
from pedenv.config import Config
from pedenv.detection import Detector, backend_options, create_detector
from pedenv.errors import InputError
from pedenv.odometry.estimator import ESTIMATED_SOURCE
from pedenv.odometry.poses_file import write_ego_poses
from pedenv.odometry.recording import posed_frames
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.outputs.output_dir import holds_files, refuse_output_dir
from pedenv.outputs.sinks import ExtraOutputs, Sinks
from pedenv.pipeline import Pipeline
from pedenv.pose.base import PoseBackend
from pedenv.pose.models import choose_input_size
from pedenv.recordings.footage import Recording
from pedenv.records import Frame
from pedenv.video_files import video_capture
from pedenv.visualize.overlay import draw_environment
from pedenv.visualize.plots import plot_birds_eye

if TYPE_CHECKING:
    from pedenv.odometry.stream import OdometryStream
    from pedenv.recordings.bag import BagRecording
    from pedenv.state import EnvironmentState


def run_recording(source: RecordingSource, output: OutputOptions | str | Path, pose: PoseOptions | None = None, *,
                  config: Config | str | Path | None = None, method: str | None = None,
                  backend: PoseBackend | None = None, pipeline: PipelineConfig | None = None,
                  progress: Callable[[int, int], None] | None = None) -> dict:
    """Run the environment model over a recording and write everything into ``output``.

    Writes ``environment.jsonl`` (a line per frame), ``config.json``, ``run.json`` (pose backend,
    frames done, speed, bytes written), ``overlays/<index>.jpg`` (``output.overlays``) or ``overlay.mp4``
    (``output.video_out``), ``birds_eye.png`` and ``.mp4`` and the ``output.extra`` outputs asked for.
    Reading, the network and writing overlap (:mod:`pedenv.apps.pipeline`, ``pipeline``; its
    ``nice`` None: chosen by the outputs, :func:`_pipeline`); every output holds the frames in
    order. A bad frame stops the run with an InputError; what was computed before it stays on
    disk. ``progress(done, total)`` is called per frame written. ``output.folder``: empty or new,
    or with ``output.overwrite`` an earlier run's, replaced when the new one has finished; no output on
    an input, a full disk one error with every output valid (:mod:`pedenv.apps.output_safety`).
    A video that ends before the frame count its header gives is warned about and
    ``run.json`` says so in ``ended_early``.
    ``pose.detection`` (``onnx``): ``stream`` (the default: the whole-frame pass, the tracks it
    missed in packed inputs and the far band's tiles in rotation, about one pass's cost), ``far``
    (whole frame + tiles over the far band) or ``fast`` (one pass fitted to the camera's aspect);
    None with ``pose.input_size`` None picks 384x640 for wide cameras, else 640 (one pass).
    Each frame runs :class:`pedenv.Pipeline`: predict the tracks, detect with them, update the model.
    ``pose.device`` (``onnx``): ``auto``,
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
    source, estimated = estimate_for_source(check_before_prepasses(source, output, config), pose, backend)
    pipe = _pipeline(pipeline or PipelineConfig(), output)
    rec, backend, folder, (poses, stream) = _open_run(source, output, pose, cfg, pipe, backend, config)
    out, frames = folder.work, Pipeline(cfg, backend)  # each frame: predict the tracks, detect with them, update
    summary, stats = {**_start_summary(rec, cfg, folder, estimated), **_poses_note(poses, folder)}, PipelineStats()
    extra = in_work_folder(output.extra or ExtraOutputs(), folder)
    writer, sinks, finished = EnvironmentWriter(out / "environment.jsonl"), Sinks(), False
    outputs = _Outputs(out, rec, output, summary, progress)
    try:
        outputs.guard = DiskGuard([out, *outside(extra, out)], len(rec))
        sinks = live_address(extra.open(), summary)
        with writer, sinks, outputs.guard:
            outputs.writer, outputs.sinks = writer, sinks
            step, write, finish = _calibration_stages(estimated, frames.process, outputs.write)
            run_frames(_posed(rec, stream, pipe.nice), step, write, config=pipe, done=outputs.done, stats=stats)
        finish(out, summary)
        _check_ended_early(rec, stats, summary)
        finished = True
    finally:
        outputs.close()
        _estimated_poses(stream, folder, summary)
        summary["frames_done"] = writer.lines  # the frames whose every output was written
        _finish_summary(summary, out, frames, stats, pipe, outputs, sinks)
        finish_run(folder, summary, sinks, finished=finished)
    return summary


def _calibration_stages(estimated: SelfCalibration | None, step: Callable[[Frame], Any],
                        write: Callable[[Any], None]) -> tuple[Callable, Callable, Callable[[Path, dict], None]]:
    """The model step, the writer and what ends a run (``finish(folder, summary)``): as they are
    with a calibration; a camera estimated in the warm-up widens every written covariance by its
    uncertainty, and a static one is refined as the run goes
    (:class:`~pedenv.apps.calibrate.Refinement`: newer estimates for later frames, the last one
    written at the end)."""
    refined = estimated.refinement() if estimated is not None else None
    if refined is not None:
        return refined.step(step), refined.widened(write), refined.finish
    return step, estimated.widened(write) if estimated is not None else write, lambda *_: None


def _start_summary(rec: Recording | BagRecording, cfg: Config, folder: RunFolder,
                   estimated: SelfCalibration | None) -> dict[str, Any]:
    """The start of ``run.json``; a camera estimated in the warm-up is written beside it
    (``calibration.yaml`` with ``estimated: true``, ``.json`` and ``.png``) and named there."""
    summary: dict[str, Any] = {"recording": rec.name, "method": cfg.method, "pose_backend": {},
                               "frames_total": len(rec), "frames_done": 0,
                               "environment": str(folder.final / "environment.jsonl")}
    if estimated is not None:
        summary["calibration"] = estimated.write(folder.work)
    return summary


def _open_run(source: RecordingSource, output: OutputOptions, pose: PoseOptions, cfg: Config,
              pipe: PipelineConfig, backend: PoseBackend | None, config: Config | str | Path | None
              ) -> tuple[Recording | BagRecording, PoseBackend, RunFolder, tuple[dict | None, OdometryStream | None]]:
    """Everything checked before the output folder is touched (the extra outputs, ``--realtime``'s
    timestamps, the recording, no output on an input, every frame of a folder or video), then the
    folder prepared and ``config.json`` saved: (recording, pose backend, output folder, (what ``run.json``
    says of the ego poses, the visual odometry's stage of a vehicle without them:
    :meth:`~pedenv.apps.options.RecordingSource.load_for_frame_loop`))."""
    (output.extra or ExtraOutputs()).check()
    source.check_realtime(pipe.realtime)
    check_run_paths(source, output, config)
    rec, poses, stream = source.load_for_frame_loop()  # a vehicle without ego poses: visual odometry in the loop
    backend = backend or _make_backend(pose, cfg, rec)
    if hasattr(rec, "check") and holds_files(Path(output.folder)):  # an earlier run there: every frame's size
        rec.check()  # and ego pose checked before it is touched (a bag is read once, as it runs); in a new folder
        # the frames before a bad one are run and stay on disk
    folder = open_run_folder(output.folder, overwrite=output.overwrite, command="pedenv run")
    cfg.save(folder.work / "config.json")
    return rec, backend, folder, (poses, stream)


def _posed(rec: Recording | BagRecording, stream: OdometryStream | None, nice: int | None) -> Iterable[Frame]:
    """The frames the reader hands on: the recording's, each with its ego pose from the visual odometry's
    stage where it estimates them (run in the reader's thread, beside the network:
    :func:`pedenv.odometry.recording.posed_frames`, the frames decoded ahead of it in a thread of their own,
    niced by ``nice``: :func:`pedenv.apps.pipeline.decoded_ahead`)."""
    if stream is None:
        return rec.frames()
    return posed_frames(decoded_ahead(rec.frames(), nice), stream, rec.name)


def _estimated_poses(stream: OdometryStream | None, folder: RunFolder, summary: dict) -> None:
    """The poses the visual odometry gave the frames, written as ``ego_poses_estimated.csv``, and what
    ``run.json`` says of them (``ego_poses``), also when the run stopped early (the frames that had poses)."""
    if stream is None:
        return
    trajectory, file = stream.trajectory(), None  # no frame had its pose: no file (``file`` null)
    if trajectory is not None:
        write_ego_poses(folder.work / ESTIMATED_SOURCE, trajectory)
        file = str(folder.final / ESTIMATED_SOURCE)
    summary["ego_poses"] = {**stream.report(), "file": file}


def check_before_prepasses(source: RecordingSource, output: OutputOptions,
                           config: Config | str | Path | None) -> RecordingSource:
    """``source``, once what refuses a run is checked before any pre-pass reads the recording (the static
    camera's warm-up, the check of a ``--static`` camera) or the visual odometry estimates its poses: no
    output on an input, an output folder that would be refused
    (:func:`~pedenv.outputs.output_dir.refuse_output_dir`), then a camera declared ``--static`` whose view
    moves (:func:`pedenv.odometry.static_check.check_static`). Any other run checks its output folder after
    the recording, as :func:`_open_run` does (a bad input is named first)."""
    check_run_paths(source, output, config)
    if source.bag is not None or not (source.static or source.ego_poses is None or needs_estimate(
            source.images, source.video, source.calibration, source.static)):
        return source
    refuse_output_dir(output.folder, overwrite=output.overwrite)
    if source.static and (source.images is not None or source.video is not None):
        from pedenv.odometry.static_check import check_static

        check_static(images=source.images, video=source.video)
    return source


def _poses_note(poses: dict | None, folder: RunFolder) -> dict[str, Any]:
    """``run.json``'s ``ego_poses``: where the poses came from (given, a static camera, or estimated from the
    images, with the estimate's file where it will be and the frames it could not measure); none for a bag."""
    if poses is None:
        return {}
    if poses.get("file") == ESTIMATED_SOURCE:
        poses = {**poses, "file": str(folder.final / ESTIMATED_SOURCE)}
    return {"ego_poses": poses}


#: ``pipeline.nice`` of ``pedenv run`` when none is given and its writer is lighter than the network.
WRITER_NICE = 10


def _pipeline(pipe: PipelineConfig, output: OutputOptions) -> PipelineConfig:
    """``pipe`` with ``nice`` chosen when it is None: :data:`WRITER_NICE` for the light outputs
    (overlay.mp4 or stored PNGs, about 11 ms of CPU per 1600x900 frame with the bird's-eye video
    and the JSON Lines), 0 for deflated PNGs (about 45 ms: on 2 cores more than the network's
    share, docs/speed.md)."""
    if pipe.nice is not None:
        return pipe
    light = output.video_out or output.overlays == "jpeg" or output.png_compression == "none"
    return dataclasses.replace(pipe, nice=WRITER_NICE if light else 0)


def _make_backend(pose: PoseOptions, cfg: Config, rec: Recording | BagRecording) -> PoseBackend:
    """The pose backend ``pose`` describes; onnx without a detection mode, input size or model
    takes the input size fitted to the recording's camera."""
    name = pose.backend or "onnx"
    input_size: str | tuple[int, int] | None = pose.input_size
    if name == "onnx" and input_size is None and pose.model is None and pose.detection is None:
        input_size = choose_input_size(rec.camera.width, rec.camera.height)
    return create_detector(name, **backend_options(
        name, pose.model, input_size, cfg.detection if pose.detection else None,
        cfg.tracking.pose_score_threshold, device=pose.device, redetect=cfg.redetect))


def _check_ended_early(rec: Recording | BagRecording, stats: PipelineStats, summary: dict) -> None:
    """A video that ended before its header's frame count: warned about and noted in ``summary``; a bag
    that gave fewer frames than it announces: noted (the bag warned when it found out)."""
    bag_note = getattr(rec, "ended_early", None)
    if bag_note:
        summary["ended_early"] = bag_note
    elif rec.video is not None and stats.taken + stats.dropped < summary["frames_total"]:
        summary["ended_early"] = (f"{rec.video}: the video ended after {stats.taken + stats.dropped} of the "
                                  f"{summary['frames_total']} frames its header announces (cut or damaged?)")
        warnings.warn(summary["ended_early"], stacklevel=3)


def _finish_summary(summary: dict, out: Path, pipeline: Pipeline, stats: PipelineStats, pipe: PipelineConfig,
                    outputs: _Outputs, sinks: Sinks) -> None:
    """The end of ``run.json``: backend, dropped frames, speed, the bird's-eye plot and the files written."""
    backend = pipeline.detector
    summary["pose_backend"] = backend.describe() if hasattr(backend, "describe") else {"backend": backend.name}
    summary["frames_dropped"] = stats.dropped
    summary["speed"] = {**stats.to_dict(), **_step_times(pipeline), "pipeline": dataclasses.asdict(pipe)}
    if outputs.last is not None:
        state, frame = outputs.last
        try:
            summary["birds_eye"] = str(plot_birds_eye(state, out / "birds_eye.png", frame, title=summary["recording"]))
        except OSError as exc:  # a full disk: run.json is written all the same
            summary["birds_eye"] = f"not written: {exc.strerror or exc}"
    summary["files"] = [str(p) for p in sinks.files]


def detection_mode(cfg: Config, pose_backend: str, detection: str | None) -> Config:
    """``cfg`` with ``detection.mode`` set to a command's ``--detection`` (onnx backend), so the
    ``config.json`` of the run records the passes that ran."""
    return cfg.replace(detection={"mode": detection}) if pose_backend == "onnx" and detection else cfg


def _step_times(pipeline: Pipeline) -> dict:
    """ms per frame of detection (the network, pre- and post-processing, the track search), the
    model's update and the network alone (an onnx detector's session runs), and network passes per frame."""
    n = max(pipeline.frames, 1)
    times = {"detection_ms_per_frame": 1e3 * pipeline.detection_s / n, "model_ms_per_frame": 1e3 * pipeline.model_s / n}
    if isinstance(pipeline.detector, Detector):
        network = pipeline.detector.network
        times.update(network_ms_per_frame=1e3 * network.network_s / n,
                     network_passes_per_frame=network.network_runs / n)
    return times


class _Outputs:
    """The writer stage: each frame's state to the JSON Lines file and the sinks, its overlay
    to a PNG or the overlay video; counts the frames written into ``summary``."""

    def __init__(self, out: Path, rec: Recording | BagRecording, output: OutputOptions, summary: dict,
                 progress: Callable[[int, int], None] | None) -> None:
        self.out, self.rec, self.summary, self.progress = out, rec, summary, progress
        self.overlays = OverlayWriter(out, output, partial(_video_rate, rec))
        self.writer: EnvironmentWriter | None = None
        self.sinks: Sinks | None = None
        self.guard: DiskGuard | None = None
        self.last: tuple | None = None  # (state, frame) of the last frame written

    def write(self, result: tuple[EnvironmentState, Frame]) -> None:
        """The overlay, the sinks, then the JSON Lines (so its lines count the frames fully written)."""
        state, frame = result
        assert self.writer is not None and self.sinks is not None and self.guard is not None  # set before the run
        try:
            self.guard.check(self.summary["frames_done"])
            if frame.image is None:
                raise InputError(f"{self.rec.name}: frame {frame.index} has no image")
            self.overlays.write(frame.index, draw_environment(frame.image, state, frame))
            self.sinks.write(state, frame)
            self.writer.write(state)
        except BaseException:
            self.guard.release()  # the outputs close next: the room kept back is theirs
            raise
        self.last = (state, frame)

    def done(self, result: tuple[EnvironmentState, Frame]) -> None:  # noqa: ARG002 - the pipeline's done(result) callback
        self.summary["frames_done"] += 1
        if self.progress is not None:
            self.progress(self.summary["frames_done"], self.summary["frames_total"])

    def close(self) -> None:
        self.overlays.close()


def _video_rate(rec: Recording | BagRecording) -> float:
    """The overlay video's frame rate: the recording's (clamped by :class:`pedenv.video_files.VideoOut`)."""
    step = float(np.median(np.diff([t for _, t in rec.images]))) if len(rec.images) > 1 else 0.0
    rate = rec.fps or (1.0 / step if step > 0 else 10.0)
    if rec.video is not None and not rec.fps:
        with video_capture(rec.video) as cap:
            rate = cap.get(cv2.CAP_PROP_FPS) or rate
    return rate
