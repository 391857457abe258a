"""ego_poses_estimated.csv: the --ego-poses format, read back by the recordings' loader."""

from __future__ import annotations

import numpy as np
from road_scene import vehicle_pose

from pedenv.geometry import rotation_to_quaternion
from pedenv.odometry.estimator import chain_poses
from pedenv.odometry.poses_file import write_ego_poses
from pedenv.recordings.ego_poses import EgoTrajectory, load_ego_poses


def test_estimated_poses_round_trip_through_the_ego_poses_loader(tmp_path):
    poses = np.array([vehicle_pose(1.5 * i, 0.1 * i * i, 3.0 * i) for i in range(4)])
    poses[:, 2, 3] = [0.0, 0.01, -0.02, 0.005]
    quats = np.array([rotation_to_quaternion(p[:3, :3]) for p in poses])
    written = EgoTrajectory(np.array([10.0, 10.1, 10.2, 10.3]), poses[:, :3, 3], quats, "estimated")
    read = load_ego_poses(write_ego_poses(tmp_path / "ego_poses_estimated.csv", written))
    np.testing.assert_allclose(read.timestamps, written.timestamps, atol=1e-9)
    np.testing.assert_allclose(read.translations, written.translations, atol=1e-9)
    np.testing.assert_allclose(read.quaternions, written.quaternions, atol=1e-9)
    pose = read.at(10.2)
    assert pose is not None
    np.testing.assert_allclose(pose.rotation, poses[2, :3, :3], atol=1e-9)


def test_chained_steps_follow_a_turning_drive():
    # a camera looking ahead, 1.65 m up: steps of 1 m forward turning 5 degrees left each
    mount = np.eye(4)
    mount[:3, :3] = [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]
    mount[2, 3] = 1.65
    truth = [vehicle_pose(0.0, 0.0, 0.0)]
    for _ in range(3):
        truth.append(truth[-1] @ vehicle_pose(1.0, 0.0, 5.0))
    cams = [p @ mount for p in truth]
    steps = [np.linalg.inv(b) @ a for a, b in zip(cams, cams[1:])]  # camera 0 -> camera 1 points
    chained = chain_poses([s[:3, :3] for s in steps], [s[:3, 3] for s in steps], mount)
    np.testing.assert_allclose(chained, np.array(truth), atol=1e-9)
