"""A vehicle recording without ego poses: its poses estimated from its frames, in the frame loop
(:func:`open_for_odometry`, :func:`posed_frames`) or all before (:func:`load_with_odometry`)."""

from __future__ import annotations

import dataclasses
from collections import deque
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.errors import InputError
from pedenv.odometry.stream import OdometryStream
from pedenv.paths import check_path
from pedenv.recordings.footage import Recording, load_calibration, load_recording
from pedenv.records import EgoPose, Frame
from pedenv.structured_text import load_yaml


def load_with_odometry(*, calibration: str | Path, images: str | Path | None = None, video: str | Path | None = None,
                       fps: float | None = None, start_time: float | None = None) -> Recording:
    """The recording of ``images`` or ``video`` with ego poses estimated by visual odometry over
    all its frames before it is run (the poses :func:`posed_frames` gives the frame loop; its
    ``trajectory.source`` is ``ego_poses_estimated.csv``). A ``mount: static`` calibration is loaded as
    it is, without poses.

    InputError: the calibration has no ``cam_to_vehicle`` (the camera's height over the road gives
    the motion its scale), or a frame is too dark or blurred (named), or the road is never seen.
    """
    return load_with_odometry_report(calibration=calibration, images=images, video=video, fps=fps,
                                     start_time=start_time)[0]


def load_with_odometry_report(*, calibration: str | Path, images: str | Path | None = None,
                              video: str | Path | None = None, fps: float | None = None,
                              start_time: float | None = None) -> tuple[Recording, dict[str, Any] | None]:
    """:func:`load_with_odometry` and what ``run.json`` says of the poses
    (:meth:`~pedenv.odometry.stream.OdometryStream.report`; None for a ``mount: static`` calibration)."""
    frames, stream = open_for_odometry(calibration=calibration, images=images, video=video, fps=fps,
                                       start_time=start_time)
    if stream is None:
        return frames, None
    for _ in posed_frames(frames.frames(), stream, frames.name):
        pass  # each frame's pose as the run would have it
    trajectory = stream.trajectory()
    if trajectory is None:
        raise InputError(f"{frames.name}: no frames for visual odometry")
    return dataclasses.replace(frames, trajectory=trajectory), stream.report()


def open_for_odometry(*, calibration: str | Path, images: str | Path | None = None, video: str | Path | None = None,
                      fps: float | None = None, start_time: float | None = None
                      ) -> tuple[Recording, OdometryStream | None]:
    """The recording of ``images`` or ``video`` without poses yet (every frame's ``ego`` the identity until
    :func:`posed_frames` sets it) and the :class:`~pedenv.odometry.stream.OdometryStream` that estimates them
    from its frames; a ``mount: static`` calibration's recording as it is, and None.

    InputError: the calibration has no ``cam_to_vehicle`` (the camera's height over the road gives
    the motion its scale)."""
    path = check_path(calibration, "calibration")
    data = load_yaml(path, "the calibration")
    if isinstance(data, dict) and "cam_to_vehicle" not in data:
        raise InputError(f"{path}: estimating the ego motion from the images needs the camera's mounting: add "
                         "cam_to_vehicle (its height over the road and pitch) to the calibration, or give --ego-poses")
    camera = load_calibration(path)
    if camera.static:
        return load_recording(calibration=path, ego_poses=None, images=images, video=video, fps=fps,
                              start_time=start_time), None
    frames = load_recording(calibration=path, ego_poses=None, images=images, video=video, fps=fps,
                            start_time=start_time, static=True)
    return dataclasses.replace(frames, camera=camera), OdometryStream(camera.intrinsics, camera.cam_to_vehicle)


def posed_frames(frames: Iterable[Frame], stream: OdometryStream, name: str = "the recording") -> Iterator[Frame]:
    """``frames`` (with their images, in order) each with its ego pose from ``stream``, yielded as soon as the
    pose is final (:data:`~pedenv.odometry.stream.POSE_LAG_FRAMES` frames later, the rest at the end)."""
    waiting: deque[Frame] = deque()
    iterator = iter(frames)
    try:
        for frame in iterator:
            assert frame.image is not None  # a recording's frames hold their images
            waiting.append(frame)
            where = f"{frame.image_path or name}: frame {frame.index}"
            for pose in stream.add(frame.image, frame.timestamp, where=where):
                yield _posed(waiting.popleft(), pose)
        for pose in stream.finish(name):
            yield _posed(waiting.popleft(), pose)
    finally:
        close = getattr(iterator, "close", None)
        if close is not None:
            close()  # a video's capture is released here


def _posed(frame: Frame, pose: np.ndarray) -> Frame:
    return dataclasses.replace(frame, ego=EgoPose(pose[:3, 3].copy(), pose[:3, :3].copy()))
