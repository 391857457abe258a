"""Real KITTI frames 0.5 s apart (tracking 0001 frames 10, 15, 20: 5.4 m between frames) against GPS/IMU:
the road's length from aligning the road, and the motion from matched descriptors when the flow loses it."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.datasets.kitti_files import read_calib
from pedenv.images import read_image_rgb
from pedenv.odometry.estimator import VisualOdometry
from pedenv.odometry.reference import mercator_positions, read_oxts, travelled, yaw_change

from shared_paths import REAL_SAMPLES

MINI = REAL_SAMPLES / "kitti/tracking_mini/training"
OXTS = REAL_SAMPLES / "kitti/tracking_sequences/training/oxts/0001.txt"
FRAMES = (10, 15, 20)


def _drive() -> tuple[VisualOdometry, float, float]:
    mount = np.eye(4)  # KITTI's colour camera looks ahead, 1.65 m above the road
    mount[:3, :3] = [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]
    mount[2, 3] = 1.65
    odometry = VisualOdometry(read_calib(MINI / "calib/0001.txt").K, mount)
    for f in FRAMES:
        odometry.update(read_image_rgb(MINI / f"image_02/0001/{f:06d}.png"), f / 10.0, where=f"frame {f}")
    oxts = read_oxts(OXTS)[FRAMES[0]:FRAMES[-1] + 1]
    return odometry, travelled(mercator_positions(oxts)), float(np.degrees(yaw_change(oxts)))


def _check(odometry: VisualOdometry, truth_m: float, truth_yaw_deg: float) -> None:
    poses = odometry.poses()
    assert truth_m == pytest.approx(10.79, abs=0.02)  # GPS: about 10.8 m/s
    assert travelled(poses[:, :3, 3]) == pytest.approx(truth_m, rel=0.05)
    assert np.degrees(np.arctan2(poses[-1, 1, 0], poses[-1, 0, 0])) == pytest.approx(truth_yaw_deg, abs=0.3)


def test_frames_far_apart_take_the_road_length_from_aligning_the_road():
    odometry, truth, yaw = _drive()
    assert [(s.guided, s.wide) for s in odometry.steps] == [(True, False)] * 2  # the flow kept the motion
    # the first pass (6 corners a cell) keeps 133 tracks of the first step, below FIRST_PASS_MIN_TRACKS:
    # all the corners were followed (measured 244 and 230 tracks)
    assert min(s.tracks for s in odometry.steps) >= 200
    _check(odometry, truth, yaw)  # measured -0.1 %, yaw +0.05 deg


def test_when_the_flow_loses_the_frames_matched_descriptors_give_the_motion(monkeypatch):
    monkeypatch.setattr("pedenv.odometry.motion.MIN_TRACKS", 10**6)  # as if no flow track survived
    odometry, truth, yaw = _drive()
    assert [(s.guided, s.wide) for s in odometry.steps] == [(True, True)] * 2
    _check(odometry, truth, yaw)  # measured -1.6 %, yaw +0.15 deg
