"""``pedenv calibrate --odometry``: a vehicle camera's motion from its images, as an ``--ego-poses`` CSV.

Every frame of the recording (an image folder with its timestamps, or a video) goes through
:func:`pedenv.calibration.odometry.trajectory` with the people found by the pose backend left out;
the poses are written to ``ego_poses_estimated.csv`` (timestamp,x,y,z,qw,qx,qy,qz; the first
frame's vehicle frame is the world), the format ``pedenv run --ego-poses`` reads.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np

from pedenv.pose.base import PoseBackend


def estimate_ego_poses(*, output: str | Path, calibration: str | Path, images: str | Path | None = None,
                       video: str | Path | None = None, fps: float | None = None,
                       backend: PoseBackend | None = None, overwrite: bool = False) -> dict:
    """Write ``output/ego_poses_estimated.csv`` from the images' motion; ``calibration``: a full
    calibration YAML (its ``cam_to_vehicle`` gives the camera's height over the road). ``backend``:
    finds the people (their boxes left out), or None to keep every corner. Returns a summary:
    frames, distance travelled (m) and yaw change (deg) from the first to the last frame."""
    from pedenv.calibration.odometry import trajectory, write_poses
    from pedenv.outputs.output_dir import prepare_output_dir
    from pedenv.recordings.footage import load_recording

    rec = load_recording(calibration=calibration, ego_poses=None, images=images, video=video, fps=fps, static=True)
    output = prepare_output_dir(output, overwrite=overwrite, command="pedenv calibrate --odometry")
    stamps: list[float] = []
    boxes: list[np.ndarray] = []

    def frames() -> Iterator[np.ndarray]:
        for frame in rec.frames():
            assert frame.image is not None
            stamps.append(frame.timestamp)
            boxes.append(np.zeros((0, 4)) if backend is None else _boxes(backend, frame.image))
            yield frame.image

    poses = trajectory(frames(), rec.camera.intrinsics, rec.camera.cam_to_vehicle, _lagged(boxes))
    path = write_poses(output / "ego_poses_estimated.csv", np.array(stamps), poses)
    yaw = np.degrees(np.arctan2(poses[-1, 1, 0], poses[-1, 0, 0]))
    return {"frames": len(poses), "distance_m": float(np.linalg.norm(poses[-1, :3, 3])), "yaw_deg": float(yaw),
            "path_m": float(np.sum(np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1))), "file": str(path)}


def _boxes(backend: PoseBackend, image: np.ndarray) -> np.ndarray:
    detect = getattr(backend, "detect", None)
    return detect(image).boxes if detect is not None else np.zeros((0, 4))


def _lagged(boxes: list[np.ndarray]) -> Iterator[np.ndarray]:
    """The boxes of each frame, read as the frames are: the list fills while the images are yielded."""
    index = 0
    while True:
        yield boxes[index] if index < len(boxes) else np.zeros((0, 4))
        index += 1
