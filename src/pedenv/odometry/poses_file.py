"""Estimated ego poses written as a CSV file in the ``--ego-poses`` format (:mod:`pedenv.recordings.ego_poses`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pedenv.recordings.ego_poses import POSE_HEADERS, EgoTrajectory


def write_ego_poses(path: str | Path, trajectory: EgoTrajectory) -> Path:
    """Write ``trajectory`` to ``path`` as ``timestamp,x,y,z,qw,qx,qy,qz`` rows (vehicle -> world,
    seconds, metres, unit quaternions), which :func:`~pedenv.recordings.ego_poses.load_ego_poses` reads back."""
    path = Path(path)
    rows = np.column_stack([trajectory.timestamps, trajectory.translations, trajectory.quaternions])
    lines = [",".join(POSE_HEADERS[0])] + [",".join(f"{v:.9f}" for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path
