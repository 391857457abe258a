"""``pedenv calibrate``: the camera estimated from the people it sees."""

from __future__ import annotations

from pathlib import Path

import typer

from pedenv.cli.app import app
from pedenv.cli.options import Device, Overwrite, PoseModel


@app.command("calibrate")
def calibrate(
    images: Path | None = typer.Option(None, "--images", help="Folder of images (sorted by name)."),
    video: Path | None = typer.Option(None, "--video", help="Video file."),
    output: Path = typer.Option(..., "--output", help="Folder for calibration.yaml, calibration.json and "
                                                      "calibration.png."),
    static: bool = typer.Option(True, "--static/--vehicle", help="A camera fixed to the ground (the default) or "
                                                                 "on a vehicle (its origin under the camera)."),
    calibration: Path | None = typer.Option(
        None, "--calibration", help="A YAML with width, height and the intrinsics or fov_deg: the focal length "
                                    "is taken from it, the rest estimated."),
    frames: int = typer.Option(200, "--frames", min=1, max=10_000, help="Most warm-up frames (a video: also at "
                                                                        "most its first 20 s)."),
    odometry: bool = typer.Option(False, "--odometry", help="Instead: the vehicle's motion from the images "
                                                            "(needs a full --calibration): ego_poses_estimated.csv."),
    ego_poses: Path | None = typer.Option(
        None, "--ego-poses", help="--vehicle: the car's ego poses (CSV, the run's format): their step lengths give "
                                  "the camera's height from the road's image motion."),
    fps: float | None = typer.Option(None, "--fps", help="Frame rate of an image folder without timestamps.csv "
                                                         "(--odometry, --ego-poses)."),
    pose_backend: str = typer.Option("onnx", "--pose-backend", help="onnx or ultralytics."),
    pose_model: PoseModel = None,
    detection: str = typer.Option("far", "--detection", help="onnx: far (whole frame + tiles) or fast (one pass)."),
    device: Device = "auto",
    overwrite: Overwrite = False,
) -> None:
    """Estimate a camera (focal length, height, tilt, roll) from the people in its first frames."""
    from pedenv.apps.calibrate import calibrate as run_calibration
    from pedenv.apps.options import RecordingSource
    from pedenv.detection import backend_options, create_detector
    from pedenv.errors import InputError

    if ego_poses is not None and (static or odometry):
        raise InputError("--ego-poses is for the mounting of a camera on a vehicle (--vehicle, without --odometry)")

    backend = create_detector(pose_backend, **backend_options(pose_backend, pose_model, None, detection,
                                                                  device=device))
    if odometry:
        _odometry(output, calibration, images, video, fps, backend, overwrite)
        return
    source = RecordingSource(images=images, video=video, calibration=calibration, ego_poses=ego_poses, static=static,
                             fps=fps)
    summary = run_calibration(output=output, source=source, backend=backend, overwrite=overwrite, frames=frames)
    std = summary["std"]
    typer.echo(f"focal {summary['focal_px']:.0f} +- {std['focal_px']:.0f} px, height {summary['height_m']:.2f} +- "
               f"{std['height_m']:.2f} m, tilt {summary['tilt_deg']:.1f} +- {std['tilt_deg']:.1f} deg, roll "
               f"{summary['roll_deg']:.1f} +- {std['roll_deg']:.1f} deg from {summary['people']} people: "
               f"{output / 'calibration.yaml'}")


def _odometry(output: Path, calibration: Path | None, images: Path | None, video: Path | None, fps: float | None,
              backend: object, overwrite: bool) -> None:
    from pedenv.apps.odometry import estimate_ego_poses
    from pedenv.errors import InputError

    if calibration is None:
        raise InputError("--odometry needs --calibration with the camera's mounting (cam_to_vehicle)")
    result = estimate_ego_poses(output=output, calibration=calibration, images=images, video=video, fps=fps,
                                backend=backend, overwrite=overwrite)  # type: ignore[arg-type]
    typer.echo(f"{result['frames']} frames: {result['distance_m']:.2f} m travelled, yaw {result['yaw_deg']:+.2f} deg: "
               f"{result['file']}")
