"""A vehicle recording without ego poses: its poses estimated from its frames before the run."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from pedenv.errors import InputError
from pedenv.odometry.estimator import VisualOdometry
from pedenv.paths import check_path
from pedenv.recordings.footage import Recording, load_calibration, load_recording
from pedenv.structured_text import load_yaml


def load_with_odometry(*, calibration: str | Path, images: str | Path | None = None, video: str | Path | None = None,
                       fps: float | None = None, start_time: float | None = None) -> Recording:
    """The recording of ``images`` or ``video`` with ego poses estimated by visual odometry over
    all its frames (:class:`~pedenv.odometry.estimator.VisualOdometry`; its ``trajectory.source``
    is ``ego_poses_estimated.csv``). A ``mount: static`` calibration is loaded as it is, without poses.

    InputError: the calibration has no ``cam_to_vehicle`` (the camera's height over the road gives
    the motion its scale), or a frame is too dark or blurred (named), or the road is never seen.
    """
    path = check_path(calibration, "calibration")
    data = load_yaml(path, "the calibration")
    if isinstance(data, dict) and "cam_to_vehicle" not in data:
        raise InputError(f"{path}: estimating the ego motion from the images needs the camera's mounting: add "
                         "cam_to_vehicle (its height over the road and pitch) to the calibration, or give --ego-poses")
    camera = load_calibration(path)
    if camera.static:
        return load_recording(calibration=path, ego_poses=None, images=images, video=video, fps=fps,
                              start_time=start_time)
    frames = load_recording(calibration=path, ego_poses=None, images=images, video=video, fps=fps,
                            start_time=start_time, static=True)
    odometry = VisualOdometry(camera.intrinsics, camera.cam_to_vehicle)
    for frame in frames.frames():
        assert frame.image is not None  # a recording's frames hold their images
        odometry.update(frame.image, frame.timestamp, where=f"{frame.image_path or frames.video}: frame {frame.index}")
    return dataclasses.replace(frames, camera=camera, trajectory=odometry.trajectory(frames.name))
