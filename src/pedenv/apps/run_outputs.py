"""The output side of ``pedenv run`` kept apart from its frame loop: the overlays written per
frame, the paths checked against the inputs, and the end of a run (``run.json``, the bytes
written, the swap of a run written beside an earlier one: :mod:`pedenv.apps.output_safety`)."""

from __future__ import annotations

import dataclasses
import json
import socket
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from pedenv.apps.output_safety import RunFolder, bytes_written, check_paths, extra_paths, input_files
from pedenv.errors import InputError
from pedenv.outputs.png import write_jpeg, write_png
from pedenv.video_files import VideoOut

if TYPE_CHECKING:
    from pedenv.apps.options import OutputOptions, RecordingSource
    from pedenv.config import Config
    from pedenv.outputs.sinks import ExtraOutputs, Sinks

class OverlayWriter:
    """Each frame's overlay: ``overlays/<index>.jpg`` (the default), ``.png`` or one ``overlay.mp4``
    (``output.video_out``). ``rate()`` gives the video's frame rate when it opens."""

    def __init__(self, out: Path, output: OutputOptions, rate: Callable[[], float]) -> None:
        self.out, self.rate = out, rate
        self.video_out, self.kind, self.png_compression = output.video_out, output.overlays, output.png_compression
        self.video: VideoOut | None = None

    def write(self, index: int, drawn: np.ndarray) -> None:
        """``drawn``: (H, W, 3) uint8 RGB. A file cut by a full disk is removed (InputError naming it)."""
        if self.video_out:
            if self.video is None:
                self.video = VideoOut(self.out / "overlay.mp4", self.rate(), (drawn.shape[1], drawn.shape[0]),
                                      what="overlay video")
            self.video.write(cv2.cvtColor(drawn, cv2.COLOR_RGB2BGR))  # 0.2 ms; drawn[..., ::-1].copy() took 8
        elif self.kind == "jpeg":
            write_jpeg(self.out / "overlays" / f"{index:06d}.jpg", drawn)
        else:
            write_png(self.out / "overlays" / f"{index:06d}.png", drawn, self.png_compression)

    def close(self) -> None:
        if self.video is not None:
            self.video.release()
            self.video = None


def check_run_paths(source: RecordingSource, output: OutputOptions, config: Config | str | Path | None) -> None:
    """No output of the run on one of its inputs (:func:`pedenv.apps.output_safety.check_paths`), before
    the recording is read: the files given and those in the image and bag folders (links followed)."""
    inputs: list[tuple[str, Any]] = [("--images", source.images), ("--video", source.video),
                                     ("--calibration", source.calibration), ("--ego-poses", source.ego_poses),
                                     ("--bag", source.bag),
                                     ("--config", config if isinstance(config, (str, Path)) else None)]
    inputs += [("--images", path) for path in input_files(source.images)]
    inputs += [("--bag", path) for path in input_files(source.bag)]
    check_paths(inputs, extra_paths(output.extra), output.folder)


def outside(extra: ExtraOutputs, folder: Path) -> list[Path]:
    """The folders of the outputs in ``extra`` that are not inside ``folder``."""
    paths = [extra.parquet, extra.rerun, extra.mcap, extra.ros]
    return [p.parent for p in paths if p is not None and folder not in p.parents]


def in_work_folder(extra: ExtraOutputs, folder: RunFolder) -> ExtraOutputs:
    """``extra`` with the outputs inside the run's folder moved to where it writes, those outside it
    that replace an earlier file written beside it (:meth:`RunFolder.output_path`), and the
    bird's-eye video in the folder by default."""
    def place(path: Path | None) -> Path | None:
        return folder.output_path(path, extra.overwrite)

    return dataclasses.replace(extra, parquet=place(extra.parquet), rerun=place(extra.rerun), mcap=place(extra.mcap),
                               ros=place(extra.ros), birds_eye_video=folder.work_path(
                                   extra.birds_eye_video) or folder.work / "birds_eye.mp4")


def live_address(sinks: Sinks, summary: dict) -> Sinks:
    """``sinks``, with ``--live``'s address served on into ``summary["live"]``."""
    for sink in sinks.sinks:
        if getattr(sink, "port", None) is not None:
            summary["live"] = str(getattr(sink, "address", sink.path))
    return sinks


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port free on ``host`` now (``--live-port 0``: chosen here, so that it is printed before the run)."""
    with socket.socket() as probe:
        probe.bind((host, 0))
        return int(probe.getsockname()[1])


def finish_run(folder: RunFolder, summary: dict, sinks: Sinks, *, finished: bool) -> None:
    """``run.json`` (with ``bytes_written``) into the run's folder, the marker listing the run's
    files, then the new run swapped in (``finished``) or the earlier one kept."""
    summary["files"] = [str(folder.final_path(p)) for p in summary.get("files", [])]
    if "birds_eye" in summary and not summary["birds_eye"].startswith("not written"):
        summary["birds_eye"] = str(folder.final_path(summary["birds_eye"]))
    others = [Path(p) for p in sinks.files if folder.work not in Path(p).parents]
    folder.list_files("run.json")
    summary["bytes_written"] = bytes_written([folder.work, *others])  # all but run.json itself
    run_json = folder.work / "run.json"
    try:
        run_json.write_text(json.dumps(summary, indent=2, allow_nan=False) + "\n")
    except OSError as exc:
        run_json.unlink(missing_ok=True)
        raise InputError(f"{run_json}: cannot be written: {exc.strerror or exc}") from None
    finally:
        if finished:
            folder.commit(sinks.files)
        else:
            folder.abandon(summary["frames_done"], sinks.files)
