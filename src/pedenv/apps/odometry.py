"""``pedenv calibrate --odometry``: a vehicle camera's motion from its images, as an ``--ego-poses`` CSV.

Every frame of the recording (an image folder with its timestamps, or a video) goes through
:class:`pedenv.odometry.VisualOdometry` with the people found by the pose backend left out (the
frame loop of ``pedenv run`` without ``--ego-poses`` runs the same steps a few frames ahead of the
network, :mod:`pedenv.odometry.stream`);
the poses are written to ``ego_poses_estimated.csv`` (the ``--ego-poses`` format; the first
frame's vehicle frame is the world).
"""

from __future__ import annotations

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
    from pedenv.odometry.estimator import ESTIMATED_SOURCE, VisualOdometry
    from pedenv.odometry.poses_file import write_ego_poses
    from pedenv.outputs.output_dir import prepare_output_dir
    from pedenv.recordings.footage import load_recording

    rec = load_recording(calibration=calibration, ego_poses=None, images=images, video=video, fps=fps, static=True)
    output = prepare_output_dir(output, overwrite=overwrite, command="pedenv calibrate --odometry")
    odometry = VisualOdometry(rec.camera.intrinsics, rec.camera.cam_to_vehicle)
    for frame in rec.frames():
        assert frame.image is not None  # a recording's frames hold their images
        boxes = backend(frame).boxes if backend is not None else None
        where = f"{frame.image_path or rec.video}: frame {frame.index}"
        odometry.update(frame.image, frame.timestamp, boxes, where=where)
    trajectory = odometry.trajectory(rec.name)
    path = write_ego_poses(output / ESTIMATED_SOURCE, trajectory)
    poses = odometry.poses(rec.name)
    yaw = np.degrees(np.arctan2(poses[-1, 1, 0], poses[-1, 0, 0]))
    return {"frames": len(odometry.timestamps), "distance_m": float(np.linalg.norm(poses[-1, :3, 3])),
            "yaw_deg": float(yaw),
            "path_m": float(np.sum(np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1))), "file": str(path)}
