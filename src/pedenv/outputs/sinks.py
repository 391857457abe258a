"""Per-frame outputs besides JSON Lines: Parquet tables, Rerun, MCAP, the bird's-eye video.

The apps call one :class:`Sinks` per run: ``write(state, frame)`` after every frame and
``close()`` at the end (also when a frame fails), so each file holds every finished frame.
A writer whose library is missing is refused before anything runs, with one line naming
the install command (:func:`require_extra`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from pedenv.errors import InputError, require_extra
from pedenv.outputs.output_dir import check_output_file
from pedenv.records import Frame
from pedenv.state import EnvironmentState


class FrameSink(Protocol):
    """Something that records the environment model frame by frame."""

    path: Path

    def write(self, state: EnvironmentState, frame: Frame) -> None: ...

    def close(self) -> None: ...


class Sinks:
    """A list of :class:`FrameSink`; a context manager that closes them all."""

    def __init__(self, sinks: list[FrameSink] | None = None) -> None:
        self.sinks = list(sinks or [])
        self.files: list[Path] = []  # what the sinks wrote, known after close()

    def write(self, state: EnvironmentState, frame: Frame) -> None:
        """One frame to every sink; a sink that cannot write (a full disk) is one InputError naming its file."""
        for sink in self.sinks:
            try:
                sink.write(state, frame)
            except OSError as exc:
                raise InputError(f"{sink.path}: cannot be written: {exc.strerror or exc}") from None

    def close(self) -> None:
        """Close every sink, even when one of them fails (the first failure is raised)."""
        first: Exception | None = None
        for sink in self.sinks:
            self.files.extend(getattr(sink, "files", None) or ([] if getattr(sink, "port", None) else [sink.path]))
            try:
                sink.close()
            except OSError as exc:  # a full disk: one line naming the file
                first = first or InputError(f"{sink.path}: cannot be finished: {exc.strerror or exc}")
            except Exception as exc:  # noqa: BLE001 - close the others first
                first = first or exc
        self.files = list(dict.fromkeys(self.files))
        self.sinks = []
        if first is not None:
            raise first

    def __enter__(self) -> Sinks:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __len__(self) -> int:
        return len(self.sinks)


@dataclass(frozen=True)
class ExtraOutputs:
    """Which per-frame outputs a run writes, and where (None: not written).

    parquet: the environment table, one row per pedestrian and frame (pyarrow).
    matches_parquet: evaluation only, the matched prediction/ground-truth pairs (pyarrow).
    rerun: a Rerun ``.rrd`` recording (rerun-sdk); several scenes give ``<stem>-<scene>.rrd``.
    mcap: a Foxglove MCAP file (foxglove-sdk).
    ros: a rosbag2 MCAP file of ROS 2 messages (rosbags; :mod:`pedenv.outputs.ros_bag`).
    live: a TCP port on 127.0.0.1 to serve the model on as it runs (foxglove-sdk's WebSocket server).
    birds_eye_video: an mp4 of every frame from above (OpenCV, always installed).
    birds_eye_scene: the one scene the video shows (None: every scene, one after the other).
    overwrite: replace an existing ``rerun``, ``mcap`` or ``ros`` file (else it is refused, see
    :func:`~pedenv.outputs.output_dir.check_output_file`).
    """

    parquet: Path | None = None
    matches_parquet: Path | None = None
    rerun: Path | None = None
    mcap: Path | None = None
    birds_eye_video: Path | None = None
    birds_eye_scene: str | None = None
    ros: Path | None = None
    live: int | None = None
    overwrite: bool = False

    def check(self) -> None:
        """Refuse missing extras and unusable ``rerun``/``mcap`` paths before the run starts (one line
        each, see :func:`require_extra` and :func:`~pedenv.outputs.output_dir.check_output_file`)."""
        if self.parquet or self.matches_parquet:
            require_extra("pyarrow.parquet", "viz", "--parquet")
        if self.rerun:
            require_extra("rerun", "viz", "--rerun")
        if self.mcap:
            require_extra("foxglove", "viz", "--mcap")
        if self.ros:
            require_extra("rosbags", "ros", "--ros-out")
        if self.live is not None:
            require_extra("foxglove", "viz", "--live")
        if self.rerun:
            check_output_file(self.rerun, "--rerun", ".rrd", overwrite=self.overwrite)
        if self.mcap:
            check_output_file(self.mcap, "--mcap", ".mcap", overwrite=self.overwrite)
        if self.ros:
            check_output_file(self.ros, "--ros-out", ".mcap", overwrite=self.overwrite)
        if self.mcap and self.ros and Path(self.mcap).resolve() == Path(self.ros).resolve():
            raise InputError(f"--mcap and --ros-out name one file, {Path(self.ros).resolve()}: give each its own file")

    def open(self) -> Sinks:
        """The sinks for the frame-by-frame outputs (all but ``matches_parquet``)."""
        self.check()
        sinks: list[FrameSink] = []
        try:
            if self.parquet:
                from pedenv.outputs.parquet import EnvironmentTableWriter

                sinks.append(EnvironmentTableWriter(self.parquet))
            if self.rerun:
                from pedenv.outputs.rerun_log import RerunWriter

                sinks.append(RerunWriter(self.rerun))
            if self.mcap:
                from pedenv.outputs.mcap_log import McapWriter

                sinks.append(McapWriter(self.mcap))
            if self.ros:
                from pedenv.outputs.ros_bag import RosBagWriter

                sinks.append(RosBagWriter(self.ros))
            if self.live is not None:
                from pedenv.outputs.live_view import LiveViewer

                sinks.append(LiveViewer(self.live))
            if self.birds_eye_video:
                from pedenv.visualize.birds_eye_video import BirdsEyeVideo

                sinks.append(BirdsEyeVideo(self.birds_eye_video, scene=self.birds_eye_scene))
        except BaseException:
            Sinks(sinks).close()
            raise
        return Sinks(sinks)
