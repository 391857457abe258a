"""Visual odometry on an exactly known motion: a textured road seen before and after a step forward."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from pedenv.calibration.odometry import people_mask, step, trajectory, write_poses
from pedenv.errors import InputError
from pedenv.recordings.ego_poses import load_ego_poses
from pedenv.records import default_cam_to_vehicle

K = np.array([[700.0, 0.0, 500.0], [0.0, 700.0, 250.0], [0.0, 0.0, 1.0]])
HEIGHT_M = 1.5


def _road(seed: int = 0) -> np.ndarray:
    """(500, 1000) uint8: smooth random texture (the road below the horizon, far scenery above)."""
    rng = np.random.default_rng(seed)
    noise = cv2.resize(rng.uniform(0, 255, (125, 250)).astype(np.float32), (1000, 500), interpolation=cv2.INTER_CUBIC)
    return np.clip(noise, 0, 255).astype(np.uint8)


def _forward(image: np.ndarray, metres: float) -> np.ndarray:
    """``image`` after the level camera moved ``metres`` forward: the road (below the horizon row
    250) moves by its homography, the scenery above (at infinity) stays."""
    normal, t = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, -metres])
    h = K @ (np.eye(3) + np.outer(t, normal) / HEIGHT_M) @ np.linalg.inv(K)
    moved = cv2.warpPerspective(image, h, (image.shape[1], image.shape[0]), flags=cv2.INTER_CUBIC)
    moved[:262] = image[:262]
    return moved


def test_a_step_forward_is_measured_in_metres() -> None:
    prev = _road()
    s = step(prev, _forward(prev, 0.8), K, np.array([0.0, -1.0, 0.0]), HEIGHT_M)
    assert s.translation[2] == pytest.approx(0.8, rel=0.05)
    assert np.degrees(np.arccos(np.clip((np.trace(s.rotation) - 1) / 2, -1, 1))) < 0.3


def test_a_still_camera_does_not_move_and_a_blank_one_is_refused() -> None:
    prev = _road()
    poses = trajectory([cv2.cvtColor(prev, cv2.COLOR_GRAY2RGB)] * 3, K, default_cam_to_vehicle(HEIGHT_M))
    assert np.abs(poses[:, :3, 3]).max() < 0.1
    blank = np.full((500, 1000), 80, np.uint8)
    with pytest.raises(InputError, match="give --ego-poses"):
        step(blank, blank, K, np.array([0.0, -1.0, 0.0]), HEIGHT_M)


def test_poses_written_as_ego_poses_read_back(tmp_path: Path) -> None:
    poses = np.repeat(np.eye(4)[None], 3, axis=0)
    poses[:, 0, 3] = [0.0, 0.9, 1.8]
    path = write_poses(tmp_path / "ego.csv", np.array([0.0, 0.1, 0.2]), poses)
    trajectory_read = load_ego_poses(path)
    assert trajectory_read.at(0.15).translation[0] == pytest.approx(1.35)
    assert people_mask((10, 10), np.array([[2, 2, 5, 5]]))[3, 3] == 0
