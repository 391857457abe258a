"""``pedenv evaluate-detections``: person recall and precision on the real samples."""

from __future__ import annotations

import sys
from pathlib import Path

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from pedenv.cli.app import app, console, stdout_console

_out = stdout_console(None if sys.stdout.isatty() else 200)


@app.command("evaluate-detections")
def evaluate_detections_command(
    data_root: Path = typer.Option(
        ..., "--data-root", help="Folder with kitti/, mot17/, nuscenes-0061/ (e.g. ../shared/samples/real)."
    ),
    detection: str = typer.Option(
        "far", "--detection",
        help="fast (one pass), far (plus tiles over the far band) or stream (each sequence's images in order)."),
    output: Path | None = typer.Option(None, "--output", help="Folder for detections_eval.json."),
    pose_model: Path | None = typer.Option(
        None, "--pose-model", help="ONNX file (default: the prepared dynamic model)."
    ),
    threads: int = typer.Option(2, "--threads", help="onnxruntime threads."),
) -> None:
    """Recall by person height and distance, precision and ms per frame of the onnx pose backend on real images."""
    from pedenv.apps.evaluate_detections import detection_table, distance_table, evaluate_detections

    columns = (TextColumn("images"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=console, transient=True) as bar:
        task = bar.add_task("detect", total=None)
        report = evaluate_detections(data_root, detection=detection, output=output, model_path=pose_model,
                                     threads=threads, progress=lambda done, total: bar.update(task, completed=done,
                                                                                             total=total))
    _out.print(detection_table(report, f"person detection, mode {detection}, {threads} threads"))
    _out.print(distance_table(report))
    if output is not None:
        _out.print(f"report: {output / 'detections_eval.json'}", highlight=False)
