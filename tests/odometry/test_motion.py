"""One step of visual odometry on a rendered road with exact truth, a static camera and a black image."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from road_scene import K, cam_to_vehicle, render, texture, vehicle_pose

from pedenv.errors import InputError
from pedenv.odometry.estimator import VisualOdometry
from pedenv.odometry.features import CORNERS_PER_CELL, GRID_CELLS, ranked_corners
from pedenv.odometry.motion import estimate_step, fill_lengths


def _drive(poses: list[np.ndarray], pitch_down_deg: float = 3.0, noise: float = 0.0) -> np.ndarray:
    """(T, 4, 4) the estimated vehicle -> world poses of frames rendered at ``poses``."""
    mount, tex, rng = cam_to_vehicle(pitch_down_deg), texture(), np.random.default_rng(1)
    odometry = VisualOdometry(K, mount)
    for i, pose in enumerate(poses):
        image = render(tex, pose, mount).astype(np.float64)
        image = np.clip(image + rng.normal(0.0, noise, image.shape), 0, 255).astype(np.uint8)
        odometry.update(image, 0.1 * i, where=f"frame {i}")
    return odometry.poses()


@pytest.mark.parametrize("step_m, yaw_step_deg, pitch_down_deg, tolerance", [
    (1.0, 0.5, 3.0, 0.02), (0.9, -0.4, 6.0, 0.02),
    (1.2, 0.0, 0.0, 0.04),  # measured -1.1 %: a level camera sees the road at a grazing angle
])
def test_a_rendered_drive_gives_its_distance_and_yaw(step_m, yaw_step_deg, pitch_down_deg, tolerance):
    truth = [vehicle_pose(0.0, 0.0, 0.0)]
    for _ in range(4):
        truth.append(truth[-1] @ vehicle_pose(step_m, 0.0, yaw_step_deg))
    poses = _drive(truth, pitch_down_deg)
    distance = np.linalg.norm(np.diff(poses[:, :3, 3], axis=0), axis=1).sum()
    yaw = np.degrees(np.arctan2(poses[-1, 1, 0], poses[-1, 0, 0]))
    assert distance == pytest.approx(4 * step_m, rel=tolerance)
    assert yaw == pytest.approx(4 * yaw_step_deg, abs=0.1)


def test_a_static_camera_does_not_move():
    # the same view with independent sensor noise: tracks jitter, the camera stays, no keyframe is added
    mount, tex, rng = cam_to_vehicle(), texture(), np.random.default_rng(1)
    view = render(tex, vehicle_pose(0.0, 0.0, 0.0), mount).astype(np.float64)
    odometry = VisualOdometry(K, mount)
    for i in range(3):
        odometry.update(np.clip(view + rng.normal(0.0, 2.0, view.shape), 0, 255).astype(np.uint8), 0.1 * i)
    trajectory = odometry.trajectory()
    np.testing.assert_allclose(trajectory.timestamps, [0.0, 0.2])
    assert np.abs(trajectory.translations).max() < 0.01
    np.testing.assert_allclose(trajectory.quaternions, [[1.0, 0.0, 0.0, 0.0]] * 2)


def test_a_creeping_car_adds_up_its_motion():
    # 4 cm a frame moves the image less than the parallax threshold: keyframes wait until it shows
    poses = [vehicle_pose(0.04 * i, 0.0, 0.0) for i in range(9)]
    mount, tex = cam_to_vehicle(), texture()
    odometry = VisualOdometry(K, mount)
    for i, pose in enumerate(poses):
        odometry.update(render(tex, pose, mount), 0.1 * i)
    keys = np.array(odometry.key_timestamps)
    assert 2 < len(keys) < 9
    forward = odometry.poses()[:, 0, 3]
    np.testing.assert_allclose(forward, 0.4 * keys, atol=0.05 * 0.4 * keys[-1])  # 4 cm per 0.1 s, within 5 %
    trajectory = odometry.trajectory()  # the frames after the last keyframe stay at its pose
    assert trajectory.timestamps[-1] == pytest.approx(0.8) and trajectory.translations[-1, 0] == forward[-1]


@pytest.mark.parametrize("spoil", [
    lambda image: np.zeros_like(image),  # black
    lambda image: (image * 0.05).astype(np.uint8),  # a twentieth of the light (a tenth still works)
    lambda image: cv2.GaussianBlur(image, (0, 0), 8.0),  # blurred over 8 px
])
def test_a_dark_or_blurred_image_is_one_input_error_naming_the_frame(spoil):
    mount, tex = cam_to_vehicle(), texture()
    first, second = (spoil(render(tex, vehicle_pose(x, 0.0, 0.0), mount)) for x in (0.0, 1.0))
    with pytest.raises(InputError, match=r"^night\.png: too dark, blurred or covered for visual odometry: 0 tracks"):
        estimate_step(first, second, K, mount, where="night.png")


def test_a_clear_frame_then_a_black_one_is_one_input_error():
    # the clear frame's corners track nowhere into the black one (no track at all on the half image)
    mount, tex = cam_to_vehicle(), texture()
    first = render(tex, vehicle_pose(0.0, 0.0, 0.0), mount)
    with pytest.raises(InputError, match=r"^day\.png: too dark, blurred or covered for visual odometry: 0 tracks"):
        estimate_step(first, np.zeros_like(first), K, mount, where="day.png")


def test_a_slightly_blurred_image_still_gives_the_step():
    mount, tex = cam_to_vehicle(), texture()
    first, second = (cv2.GaussianBlur(render(tex, vehicle_pose(x, 0.0, 0.0), mount), (0, 0), 2.0) for x in (0.0, 1.0))
    assert estimate_step(first, second, K, mount).length == pytest.approx(1.0, rel=0.03)


def test_people_boxes_are_left_out():
    mount, tex = cam_to_vehicle(), texture()
    first, second = (render(tex, vehicle_pose(x, 0.0, 0.0), mount) for x in (0.0, 1.0))
    everywhere = np.array([[0.0, 0.0, 640.0, 360.0]])
    with pytest.raises(InputError, match="0 tracks"):
        estimate_step(first, second, K, mount, boxes=everywhere, where="crowd")
    assert estimate_step(first, second, K, mount, boxes=np.array([[0.0, 0.0, 320.0, 180.0]])).length \
        == pytest.approx(1.0, rel=0.02)


@pytest.mark.parametrize("lengths, durations, expected", [
    ([1.0, np.nan, 2.0], [0.1, 0.1, 0.1], [1.0, 1.5, 2.0]),
    ([np.nan, 1.0, 0.0], [0.1, 0.1, 0.2], [1.0, 1.0, 0.0]),
    ([0.0, 0.0], [0.1, 0.1], [0.0, 0.0]),
    ([1.0, np.nan], [0.1, 0.2], [1.0, 2.0]),
])
def test_steps_without_the_road_take_their_neighbours_speed(lengths, durations, expected):
    np.testing.assert_allclose(fill_lengths(np.array(lengths), np.array(durations)), expected)


def test_no_road_at_all_is_one_input_error():
    with pytest.raises(InputError, match="^drive.mp4: visual odometry saw no road ahead of the camera"):
        fill_lengths(np.array([np.nan, np.nan]), np.array([0.1, 0.1]), "drive.mp4")


def test_a_long_drive_pools_the_pitch_and_lets_the_road_tracks_go(monkeypatch):
    monkeypatch.setattr("pedenv.odometry.estimator.PITCH_POOL_STEPS", 2)
    mount, tex = cam_to_vehicle(), texture()
    odometry = VisualOdometry(K, mount)
    for i in range(4):
        odometry.update(render(tex, vehicle_pose(1.0 * i, 0.0, 0.0), mount), 0.1 * i)
    assert [len(s.road[0]) for s in odometry.steps[:2]] == [0, 0] and len(odometry.steps[2].road[0]) > 15
    np.testing.assert_allclose(odometry.lengths(), 1.0, rtol=0.03)
    assert all(len(s.road[0]) == 0 for s in odometry.steps)


def test_the_road_alignment_finds_a_long_rendered_step():
    # 4 m between two rendered frames: the road's own alignment (frames far apart) against the exact truth
    from pedenv.odometry.ground import guided_road_length

    mount, tex = cam_to_vehicle(), texture()
    first, second = (render(tex, vehicle_pose(x, 0.0, 0.0), mount) for x in (0.0, 4.0))
    forward, up = (mount[:3, :3].T @ axis for axis in np.eye(3)[[0, 2]])  # the vehicle's x and z, camera frame
    distance = guided_road_length(first, second, K, np.eye(3), -forward, mount)  # camera points move back
    assert mount[2, 3] / distance == pytest.approx(4.0, rel=0.05)
    assert np.isnan(guided_road_length(first, second, K, np.eye(3), up, mount))  # no motion along the road


def test_corners_come_each_cells_strongest_first():
    image = render(texture(), vehicle_pose(0.0, 0.0, 0.0), cam_to_vehicle())
    corners, rank = ranked_corners(image, np.full(image.shape, 255, np.uint8))
    rows, cols = GRID_CELLS
    cell = (np.minimum(corners[:, 1] * rows // image.shape[0], rows - 1) * cols
            + np.minimum(corners[:, 0] * cols // image.shape[1], cols - 1)).astype(int)
    assert len(corners) > 10 * rows * cols // 2  # a textured road and walls: most cells full
    assert np.all(np.diff(rank) >= 0) and rank.max() == CORNERS_PER_CELL - 1
    first = rank == 0
    assert len(np.unique(cell[first])) == first.sum() == len(np.unique(cell))  # one per cell that has any
    assert np.bincount(cell).max() == CORNERS_PER_CELL
