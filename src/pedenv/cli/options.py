"""The flags shared by ``run``, ``evaluate``, ``demo``, ``detect`` and ``bench``, declared once.

Each alias is a ``typing.Annotated`` type that carries its ``typer.Option``; a command gives
the default in its own signature (``detection: Detection = "far"``), so two commands can
share a flag and its help while their defaults differ.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

ConfigFile = Annotated[Path | None, typer.Option(
    "--config", help="A config.json of the environment model to use instead of the defaults.")]
Overwrite = Annotated[bool, typer.Option(
    "--overwrite", help="Replace the outputs of an earlier run in --output, and an existing --rerun/--mcap/--ros-out "
                        "file.")]
Parquet = Annotated[bool, typer.Option(
    "--parquet", help="Also write environment.parquet (one row per pedestrian and frame; and matches.parquet when "
                      "evaluating).")]
RerunOption = Annotated[Path | None, typer.Option(
    "--rerun", help="Write a Rerun recording (FILE.rrd; one file per scene when several; an existing file only with "
                    "--overwrite).")]
Mcap = Annotated[Path | None, typer.Option(
    "--mcap", help="Write a Foxglove MCAP file (FILE.mcap; an existing file only with --overwrite).")]
RosOut = Annotated[Path | None, typer.Option(
    "--ros-out", help="Write ROS 2 messages (vision_msgs, RViz markers, /tf, Autoware) as a rosbag2 FILE.mcap "
                      "(FILE-<method>.mcap with --method both).")]

PoseModel = Annotated[Path | None, typer.Option(
    "--pose-model", help="ONNX file (onnx) or .pt weights (ultralytics).")]
PoseInputSize = Annotated[str | None, typer.Option(
    "--pose-input-size", help="Network input, 640 or 384x640 (run's default: by camera aspect).")]
Detection = Annotated[str | None, typer.Option(
    "--detection", help="onnx: far (whole frame + tiles over the far band; detect's and evaluate's "
                        "default), stream (far over consecutive frames, within a budget; run's default) or fast "
                        "(one pass).")]
Device = Annotated[str, typer.Option(
    "--device", help="onnx: auto (the GPU when onnxruntime has one, else the CPU), cpu or cuda (a GPU or an "
                     "error).")]

Executor = Annotated[str, typer.Option(
    "--executor", help="serial (in this process) or ray (one task per scene, or per recording of a --manifest).")]
Address = Annotated[str | None, typer.Option(
    "--address", help="Ray cluster HOST:PORT (`ray start --head`); default: a local Ray.")]
Workers = Annotated[int | None, typer.Option(
    "--workers", help="Ray: CPUs of the local Ray, or most tasks at once on a cluster.")]
ObjectStore = Annotated[int | None, typer.Option(
    "--object-store-memory", help="Ray: bytes of the local Ray's object store (default: a tenth of memory, at most "
                                  "2 GiB).")]
Resume = Annotated[bool, typer.Option(
    "--resume", help="Keep the scenes (or --manifest recordings) an earlier run in --output completed; run the "
                     "rest.")]


def split_names(text: str | None) -> tuple[str, ...] | None:
    """A comma-separated flag (``--scenes a,b``, ``--cues ground,height``) as names; None when not given."""
    return tuple(s.strip() for s in text.split(",") if s.strip()) if text else None
