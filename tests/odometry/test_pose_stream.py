"""The visual odometry as a stage of the frame loop: each frame's pose handed on a few frames later, never changed."""

from __future__ import annotations

import numpy as np
import pytest
from road_scene import K, cam_to_vehicle, render, texture, vehicle_pose

from pedenv.errors import InputError
from pedenv.odometry.stream import OdometryStream


def _handed_on(views: list[np.ndarray], mount: np.ndarray, lag: int) -> tuple[list[list[np.ndarray]], OdometryStream]:
    """The poses handed on after each frame (0.1 s apart), then at the end, and the stream."""
    stream, handed = OdometryStream(K, mount, lag=lag), []
    for i, view in enumerate(views):
        handed.append(stream.add(view, 0.1 * i, where=f"frame {i}"))
    handed.append(stream.finish())
    return handed, stream


def test_poses_are_handed_on_lag_frames_behind_and_later_frames_do_not_change_them():
    mount, tex = cam_to_vehicle(), texture()
    straight = [vehicle_pose(0.9 * i, 0.0, 0.0) for i in range(6)]
    turning = straight[:4]
    for _ in range(2):  # the same first four frames, then a left turn of 3 degrees a frame
        turning.append(turning[-1] @ vehicle_pose(0.9, 0.0, 3.0))
    ahead, stream = _handed_on([render(tex, p, mount) for p in straight], mount, lag=2)
    turned, _ = _handed_on([render(tex, p, mount) for p in turning], mount, lag=2)
    assert [len(p) for p in ahead] == [0, 0, 1, 1, 1, 1, 2]  # frame i's pose once frame i + 2 was estimated
    for before, after in zip(ahead[:4], turned[:4]):  # handed on before the turn was seen: the same poses
        assert len(before) == len(after) and all(np.array_equal(a, b) for a, b in zip(before, after))
    poses = np.array([p for batch in ahead for p in batch])
    np.testing.assert_allclose(poses[:, 0, 3], [0.9 * i for i in range(6)], atol=0.02 * 4.5)  # 2 % of the drive
    yaw = [np.degrees(np.arctan2(p[1, 0], p[0, 0])) for batch in turned for p in batch]
    assert yaw[-1] == pytest.approx(6.0, abs=0.1)
    assert stream.report()["frames"] == 6 and stream.report()["keyframes"] == 6 and stream.report()["lag_frames"] == 2


def test_frames_between_keyframes_are_placed_between_them():
    # 4 cm a frame moves the image less than the parallax threshold: keyframes every few frames, the frames
    # between them interpolated as the next keyframe comes within the lag
    mount, tex = cam_to_vehicle(), texture()
    handed, stream = _handed_on([render(tex, vehicle_pose(0.04 * i, 0.0, 0.0), mount) for i in range(9)], mount, lag=4)
    assert 2 < len(stream.key_frames) < 9
    forward = np.array([p[0, 3] for batch in handed for p in batch])
    last_key = stream.key_frames[-1]  # the frames after the last keyframe stay at its pose
    np.testing.assert_allclose(forward[:last_key + 1], 0.04 * np.arange(last_key + 1), atol=0.05 * 0.04 * last_key)
    assert np.all(forward[last_key:] == forward[last_key])


def test_a_timestamp_out_of_order_is_one_line():
    mount, tex = cam_to_vehicle(), texture()
    stream = OdometryStream(K, mount)
    stream.add(render(tex, vehicle_pose(0.0, 0.0, 0.0), mount), 1.0, where="a.png")
    with pytest.raises(InputError, match=r"^b\.png: timestamp 0\.500000 s is not after the previous frame's 1\.0+ s"):
        stream.add(render(tex, vehicle_pose(0.9, 0.0, 0.0), mount), 0.5, where="b.png")


def test_a_step_without_the_road_takes_its_neighbours_speed():
    # steps of 1 m in 0.1 s and 3 m in 0.1 s around a step of 0.2 s whose road gave no length: 20 m/s between them
    # (fill_lengths, as the whole recording's estimate fills it), never changed once handed on
    from pedenv.odometry.motion import Step

    mount = cam_to_vehicle()
    stream = OdometryStream(K, mount)
    forward = -mount[:3, :3].T @ np.array([1.0, 0.0, 0.0])  # the car moving forward: the world moves back
    stream.timestamps, stream.key_frames = [0.0, 0.1, 0.3, 0.4], [0, 1, 2, 3]
    stream.steps = [Step(np.eye(3), forward, 1.0, 100, 100, 5.0, guided=True),
                    Step(np.eye(3), forward, float("nan"), 100, 100, 5.0),  # no road tracks: no length
                    Step(np.eye(3), forward, 3.0, 100, 100, 5.0, guided=True)]
    poses = stream.finish()
    np.testing.assert_allclose(stream.lengths, [1.0, 4.0, 3.0])
    assert stream.filled == [False, True, False]
    np.testing.assert_allclose([p[0, 3] for p in poses], [0.0, 1.0, 5.0, 8.0], atol=1e-9)
    assert stream.report()["frames_without_road_scale"] == [2]
