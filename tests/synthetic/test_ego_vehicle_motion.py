"""Ego motion: integration of the profiles, pitch and roll from terrain and suspension, the turn."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.synthetic.ego_motion import ego_poses, integrate_track, smooth_step
from pedenv.synthetic.terrain import Terrain


def ypr(pose):
    r = pose.rotation
    return np.arctan2(r[1, 0], r[0, 0]), np.arcsin(-r[2, 0]), np.arctan2(r[2, 1], r[2, 2])


def test_straight_and_circular_tracks():
    t = np.arange(0, 10, 0.1)
    straight = integrate_track(t, lambda s: np.full_like(s, 10.0), lambda s: np.zeros_like(s))
    np.testing.assert_allclose(straight.xy[:, 0], 10 * t, atol=1e-9)
    # 5 m/s at 0.5 rad/s: a circle of radius 10 m centred at (0, 10)
    circle = integrate_track(t, lambda s: np.full_like(s, 5.0), lambda s: np.full_like(s, 0.5))
    np.testing.assert_allclose(np.linalg.norm(circle.xy - [0, 10], axis=1), 10.0, atol=1e-3)
    np.testing.assert_allclose(circle.yaw, 0.5 * t, atol=1e-9)


def test_smooth_step_ramps():
    assert smooth_step(np.array([0.0, 1.0, 1.5, 2.0, 3.0]), 1.0, 1.0) == pytest.approx([0, 0, 0.5, 1, 1])


@pytest.mark.parametrize("yaw", [0.0, np.pi / 2])
def test_pitch_follows_the_slope_and_the_suspension(yaw):
    # a 4 % slope up along the heading: nose up = negative pitch of atan(0.04) = -2.29 deg
    k = 2 * np.pi / 10000.0
    direction = np.array([np.cos(yaw), np.sin(yaw)])
    hill = Terrain(np.array([0.04 / k]), (k * direction)[None], np.zeros(1))
    t = np.array([0.0, 1.0, 2.0])
    still = integrate_track(t, lambda s: np.zeros_like(s), lambda s: np.zeros_like(s), start_yaw=yaw)
    accelerating = integrate_track(t, lambda s: 2.0 * s, lambda s: np.zeros_like(s), start_yaw=yaw)
    _, pitch, roll = ypr(ego_poses(still, hill)[0])
    assert np.degrees(pitch) == pytest.approx(-2.29, abs=0.01) and roll == pytest.approx(0.0, abs=1e-6)
    # 2 m/s^2 adds 1 deg of nose-up squat
    assert np.degrees(ypr(ego_poses(accelerating, hill)[1])[1]) == pytest.approx(-3.29, abs=0.02)


def test_roll_from_a_side_slope_and_z_on_the_terrain():
    k = 2 * np.pi / 10000.0
    side_slope = Terrain(np.array([0.03 / k]), np.array([[0.0, k]]), np.zeros(1))  # rises towards +y
    track = integrate_track(np.array([0.0, 1.0]), lambda s: np.zeros_like(s), lambda s: np.zeros_like(s),
                            start_xy=(0.0, 100.0))
    pose = ego_poses(track, side_slope)[0]
    assert np.degrees(ypr(pose)[2]) == pytest.approx(np.degrees(np.arctan(0.03 * np.cos(k * 100))), abs=0.01)
    assert pose.translation[2] == pytest.approx(side_slope.height(np.array([0.0, 100.0])), abs=1e-3)


def test_flat_ground_never_pitches_even_when_braking():
    track = integrate_track(np.arange(0, 5, 0.1), lambda s: 10 - 2 * s, lambda s: np.zeros_like(s))
    for pose in ego_poses(track, Terrain.flat()):
        assert np.array_equal(pose.rotation[2], [0.0, 0.0, 1.0]) and pose.translation[2] == 0.0
