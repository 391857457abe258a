"""The typed option groups of the applications: what a run reads, which pose network, what it writes, where it runs.

Each group is one small frozen dataclass that the commands fill from their flags and the
Python API takes as it is::

    run_recording(RecordingSource(images="frames", calibration="calibration.yaml", ego_poses="poses.csv"),
                  OutputOptions("out", overwrite=True), PoseOptions(detection="fast"))
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.outputs.png import OVERLAY_FORMATS, check_png_compression
from pedenv.outputs.sinks import ExtraOutputs

if TYPE_CHECKING:
    from pedenv.odometry.stream import OdometryStream
    from pedenv.recordings.bag import BagRecording
    from pedenv.recordings.bag_topics import BagOptions
    from pedenv.recordings.footage import Recording


@dataclass(frozen=True)
class RecordingSource:
    """A user's recording: ``images`` (a folder) or ``video``, with ``calibration`` and ``ego_poses``, or a ``bag``.

    static: the camera is fixed to the ground (``mount: static``); ``ego_poses`` may then be None.
    Without ``ego_poses`` a vehicle's are estimated from the images (:mod:`pedenv.odometry`).
    fps: frame rate when the folder has no timestamps.csv (or to override a video's), Hz.
    start_time: timestamp of the first frame with ``fps`` or a video, seconds (default: the first ego pose).
    bag: a ROS bag (rosbag2 folder, .mcap or ROS 1 .bag) instead of the files above, read with
    ``bag_options`` (:func:`pedenv.recordings.bag.load_bag_recording`).
    """

    images: str | Path | None = None
    video: str | Path | None = None
    calibration: str | Path | None = None
    ego_poses: str | Path | None = None
    static: bool = False
    fps: float | None = None
    start_time: float | None = None
    bag: str | Path | None = None
    bag_options: BagOptions | None = None

    def load(self) -> Recording | BagRecording:
        """The recording (:func:`pedenv.recordings.footage.load_recording`, or the bag's)."""
        return self.load_with_poses_note()[0]

    def load_with_poses_note(self) -> tuple[Recording | BagRecording, dict[str, Any] | None]:
        """The recording and what ``run.json`` says of its ego poses (``ego_poses``): given (their file),
        a static camera's (none), or estimated from the images
        (:func:`pedenv.odometry.recording.load_with_odometry_report`); None for a bag."""
        if self.bag is not None:
            from pedenv.recordings.bag import load_bag_recording

            return load_bag_recording(self.bag, self.bag_options), None
        from pedenv.recordings.footage import load_recording

        if self.calibration is None:
            raise InputError("a recording needs its calibration (--calibration)")
        if self.ego_poses is None and not self.static:  # a vehicle without poses: visual odometry (pedenv.odometry)
            from pedenv.odometry.recording import load_with_odometry_report

            rec, note = load_with_odometry_report(calibration=self.calibration, images=self.images, video=self.video,
                                                  fps=self.fps, start_time=self.start_time)
            return rec, note or {"source": "static camera (the calibration's mount: static)"}
        rec = load_recording(calibration=self.calibration, ego_poses=self.ego_poses, images=self.images,
                             video=self.video, fps=self.fps, start_time=self.start_time, static=self.static)
        given = {"source": "given", "file": str(self.ego_poses)} if self.ego_poses is not None else None
        return rec, given or {"source": "static camera"}

    def load_for_frame_loop(self) -> tuple[Recording | BagRecording, dict[str, Any] | None, OdometryStream | None]:
        """:meth:`load_with_poses_note`, except that a vehicle without ego poses is loaded without them and
        comes with the :class:`~pedenv.odometry.stream.OdometryStream` that estimates them in the frame loop
        (:func:`pedenv.odometry.recording.open_for_odometry`; ``pedenv run``): no pre-pass reads the frames."""
        if self.bag is not None or self.ego_poses is not None or self.static or self.calibration is None:
            return (*self.load_with_poses_note(), None)
        from pedenv.odometry.estimator import ESTIMATED_SOURCE
        from pedenv.odometry.recording import open_for_odometry

        rec, stream = open_for_odometry(calibration=self.calibration, images=self.images, video=self.video,
                                        fps=self.fps, start_time=self.start_time)
        if stream is None:
            return rec, {"source": "static camera (the calibration's mount: static)"}, None
        return rec, {"source": "estimated", "file": ESTIMATED_SOURCE}, stream

    def check_realtime(self, realtime: bool) -> None:
        """``--realtime`` on an image folder needs the frames' times: its timestamps.csv or ``fps``."""
        images = self.images
        if realtime and images is not None and self.fps is None and Path(images).is_dir() \
                and not (Path(images) / "timestamps.csv").is_file():
            raise InputError(f"{images}: --realtime takes the frames at their own times, and the folder has no "
                             "timestamps.csv (filename,timestamp); add one or give --fps")


@dataclass(frozen=True)
class PoseOptions:
    """The pose network: ``--pose-backend``, ``--pose-model``, ``--pose-input-size``, ``--detection``, ``--device``.

    backend: a registered name (None: the dataset's own, for evaluations). model: an ONNX file
    (onnx) or .pt weights (ultralytics). input_size: ``640`` or ``384x640``. detection (onnx):
    ``far``, ``stream`` or ``fast`` (None with ``input_size`` None: one pass sized by the
    camera's aspect). device (onnx): ``auto``, ``cpu`` or ``cuda``.
    """

    backend: str | None = "onnx"
    model: str | Path | None = None
    input_size: str | None = None
    detection: str | None = "stream"
    device: str = "auto"


@dataclass(frozen=True)
class OutputOptions:
    """Where a run writes and what besides its JSON Lines.

    folder: the output folder (new or empty, or an earlier pedenv run's with ``overwrite``).
    video_out: ``overlay.mp4`` instead of one PNG per frame (``pedenv run``).
    extra: Parquet, Rerun, MCAP, ROS, live and bird's-eye outputs (None: none but the default ones).
    overlays: ``jpeg`` (the default: about 0.3 MB per 1600x900 overlay) or ``png`` (lossless).
    png_compression: the overlay PNGs' deflate, ``none`` (the default) or ``fast``
        (:mod:`pedenv.outputs.png`: ``none`` writes a 1600x900 overlay in a tenth of the CPU
        time of ``fast``, 4.3 MB instead of about 1.5 MB).
    """

    folder: str | Path
    overwrite: bool = False
    video_out: bool = False
    extra: ExtraOutputs | None = None
    png_compression: str = "none"
    overlays: str = "jpeg"

    def __post_init__(self) -> None:
        check_png_compression("output.png_compression", self.png_compression)
        if self.overlays not in OVERLAY_FORMATS:
            raise InputError(f"--overlays must be one of {', '.join(OVERLAY_FORMATS)}, got {self.overlays!r}")

    @classmethod
    def of(cls, output: OutputOptions | str | Path) -> OutputOptions:
        """``output`` as OutputOptions (a bare path: that folder, nothing else asked)."""
        return output if isinstance(output, OutputOptions) else cls(output)


@dataclass(frozen=True)
class OutputFlags:
    """The command line's per-frame output flags: ``--parquet``, ``--rerun``, ``--mcap``, ``--ros-out``, ``--live``.

    live: the TCP port of ``--live`` (None: not served).
    """

    parquet: bool = False
    rerun: Path | None = None
    mcap: Path | None = None
    ros: Path | None = None
    live: int | None = None

    def extra_outputs(self, output: OutputOptions, *, matches: bool = False,
                      video_scene: str | None = None) -> ExtraOutputs:
        """The ExtraOutputs in ``output.folder``: ``matches`` adds matches.parquet to ``--parquet`` (evaluations);
        ``video_scene`` adds the bird's-eye video of that scene."""
        folder = Path(output.folder)
        return ExtraOutputs(parquet=folder / "environment.parquet" if self.parquet else None,
                            matches_parquet=folder / "matches.parquet" if self.parquet and matches else None,
                            rerun=self.rerun, mcap=self.mcap, ros=self.ros, live=self.live,
                            birds_eye_video=folder / "birds_eye.mp4" if video_scene else None,
                            birds_eye_scene=video_scene, overwrite=output.overwrite)

    def given(self) -> list[str]:
        """The flags given, in the command line's spelling."""
        names = {"parquet": "--parquet", "rerun": "--rerun", "mcap": "--mcap", "ros": "--ros-out", "live": "--live"}
        return [names[f.name] for f in fields(self) if getattr(self, f.name) not in (None, False)]


@dataclass(frozen=True)
class ExecutorOptions:
    """Where the tasks run: ``--executor``, ``--address``, ``--workers``, ``--resume``.

    name: ``serial`` (this process) or ``ray``. address: a Ray cluster ``HOST:PORT`` (None: a
    local Ray). workers: CPUs of the local Ray, or most tasks at once on a cluster.
    resume: keep what an earlier run in the output folder completed. object_store_memory:
    bytes of a local Ray's object store (None: Ray's default).
    """

    name: str = "serial"
    address: str | None = None
    workers: int | None = None
    resume: bool = False
    object_store_memory: int | None = None

    def check_serial(self) -> None:
        """Refuse ``--address`` and ``--workers`` with the serial executor."""
        if self.name == "serial" and (self.address is not None or self.workers is not None):
            raise InputError("--address and --workers apply to --executor ray")


@dataclass(frozen=True)
class MethodOptions:
    """The environment model's settings: ``--config``, ``--method`` and the paper method's flags.

    config: a Config or a config.json (None: the defaults). method: ``fused``, ``paper`` or
    (evaluations) ``both``. refine, initial_estimate: the paper method's height refinement and
    first estimate (None: the config's). cues: the fused method's cues (None: the config's).
    """

    config: Config | str | Path | None = None
    method: str | None = None
    refine: bool | None = None
    initial_estimate: str | None = None
    cues: tuple[str, ...] | None = None

    def load(self, *, allow_both: bool = False) -> Config:
        """The Config: ``config`` (or the defaults) with the paper settings given and ``method``'s preset,
        then ``cues``. ``allow_both``: ``method`` may be ``both`` (an evaluation of both methods: no preset)."""
        changes = {k: v for k, v in (("refine", self.refine), ("initial_estimate", self.initial_estimate))
                   if v is not None}
        both = allow_both and self.method == "both"
        cfg = load_config(self.config, None if both else self.method, changes)
        if (self.refine is not None or self.initial_estimate) and not both and cfg.method != "paper":
            raise InputError(f"--no-refinement and --initial-estimate change the paper's method, not {cfg.method}; "
                             "add --method paper")
        return cfg.replace(fused={"cues": self.cues}) if self.cues is not None else cfg


def load_config(config: Config | str | Path | None, method: str | None = None, paper: dict | None = None) -> Config:
    """``config`` (a Config, a config.json, or None: the defaults) with the ``paper`` settings changed and
    ``method``'s preset (:func:`pedenv.localization.configure`)."""
    from pedenv.localization import configure

    cfg = config if isinstance(config, Config) else (Config.load(config) if config else Config())
    cfg = cfg.replace(paper=paper) if paper else cfg
    return configure(cfg, method) if method else cfg
