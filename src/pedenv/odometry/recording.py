"""A vehicle recording without ego poses: its poses estimated from its frames before the run."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.errors import InputError
from pedenv.odometry.estimator import ESTIMATED_SOURCE, VisualOdometry
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
    return load_with_odometry_report(calibration=calibration, images=images, video=video, fps=fps,
                                     start_time=start_time)[0]


def load_with_odometry_report(*, calibration: str | Path, images: str | Path | None = None,
                              video: str | Path | None = None, fps: float | None = None,
                              start_time: float | None = None) -> tuple[Recording, dict[str, Any] | None]:
    """:func:`load_with_odometry` and what ``run.json`` says of the poses (:func:`odometry_report`;
    None for a ``mount: static`` calibration)."""
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
    odometry = VisualOdometry(camera.intrinsics, camera.cam_to_vehicle)
    keyframes: list[int] = []  # the index of each keyframe
    start = time.perf_counter(), time.process_time()
    for frame in frames.frames():
        assert frame.image is not None  # a recording's frames hold their images
        odometry.update(frame.image, frame.timestamp, where=f"{frame.image_path or frames.video}: frame {frame.index}")
        if len(odometry.key_timestamps) > len(keyframes):
            keyframes.append(frame.index)
    trajectory = odometry.trajectory(frames.name)
    spent = (time.perf_counter() - start[0], time.process_time() - start[1])
    report = odometry_report(odometry, keyframes, spent)
    return dataclasses.replace(frames, camera=camera, trajectory=trajectory), report


def odometry_report(odometry: VisualOdometry, keyframes: list[int], spent: tuple[float, float]) -> dict[str, Any]:
    """``run.json``'s ``ego_poses`` of estimated poses: the file, the frames and keyframes, the frames
    (each ending a step) whose length the road did not give (taken from the neighbours' speed), whose
    length came from aligning the road (frames far apart) and whose motion from matched descriptors (the
    flow lost them), and the time spent (``spent``: wall and CPU seconds)."""
    lengths = odometry.lengths()
    steps = odometry.steps
    ends = keyframes[1:]  # step i ends at keyframe i + 1
    frames = len(odometry.timestamps)
    return {
        "source": "estimated", "file": ESTIMATED_SOURCE, "frames": frames, "keyframes": len(keyframes),
        "frames_without_road_scale": [ends[i] for i, n in enumerate(lengths) if np.isnan(n)],
        "frames_scaled_by_road_alignment": [ends[i] for i, s in enumerate(steps) if s.guided],
        "frames_from_matched_descriptors": [ends[i] for i, s in enumerate(steps) if s.wide],
        "estimate_s": round(spent[0], 3), "estimate_cpu_s": round(spent[1], 3),
        "estimate_ms_per_frame": round(1e3 * spent[0] / max(frames, 1), 1),
    }
