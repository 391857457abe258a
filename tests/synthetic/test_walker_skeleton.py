"""The articulated walking skeleton: proportions, gait and placement in the world."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.body import world_keypoints
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic.walker import body_keypoints, stride_length


def standing(height: float) -> np.ndarray:
    return body_keypoints(np.array([height]), np.zeros(1), np.zeros(1), np.zeros((1, 2)))[0]


def walking(phases: np.ndarray, height: float = 1.75) -> np.ndarray:
    n = len(phases)
    return body_keypoints(np.full(n, height), phases, np.ones(n), np.zeros((n, 2)))


@pytest.mark.parametrize("height", [1.55, 1.72, 1.95])
@pytest.mark.parametrize("keypoint, fraction", [
    (KP.NOSE, 0.920), (KP.LEFT_EYE, 0.933), (KP.RIGHT_EAR, 0.915), (KP.LEFT_SHOULDER, 0.818),
    (KP.RIGHT_HIP, 0.530), (KP.LEFT_KNEE, 0.285), (KP.RIGHT_ANKLE, 0.046),
])
def test_standing_proportions_scale_with_height(height, keypoint, fraction):
    assert standing(height)[keypoint, 2] == pytest.approx(fraction * height, abs=1e-9)


def test_ankles_about_8_cm_above_ground_and_head_below_height():
    kp = standing(1.72)
    assert kp[KP.LEFT_ANKLE, 2] == pytest.approx(0.079, abs=0.002)  # 0.046 * 1.72
    assert kp[:, 2].max() < 1.72


@pytest.mark.parametrize("a, b, length", [
    (KP.LEFT_HIP, KP.LEFT_KNEE, 0.245), (KP.RIGHT_KNEE, KP.RIGHT_ANKLE, 0.239),
    (KP.LEFT_SHOULDER, KP.LEFT_ELBOW, 0.186), (KP.RIGHT_ELBOW, KP.RIGHT_WRIST, 0.146),
])
def test_segments_keep_their_length_through_the_gait(a, b, length):
    kp = walking(np.linspace(0, 2 * np.pi, 24, endpoint=False))
    np.testing.assert_allclose(np.linalg.norm(kp[:, a] - kp[:, b], axis=1), length * 1.75, rtol=1e-9)


def test_stance_foot_stays_on_the_ground():
    kp = walking(np.linspace(0, 2 * np.pi, 36, endpoint=False))
    lowest = kp[:, [KP.LEFT_ANKLE, KP.RIGHT_ANKLE], 2].min(axis=1)
    np.testing.assert_allclose(lowest, 0.046 * 1.75, atol=1e-9)


def test_legs_swing_in_anti_phase_and_arms_against_legs():
    kp = walking(np.array([np.pi / 2]))[0]  # left thigh at its most forward
    assert kp[KP.LEFT_KNEE, 0] > 0.1 > -0.1 > kp[KP.RIGHT_KNEE, 0]
    assert kp[KP.LEFT_WRIST, 0] < kp[KP.RIGHT_WRIST, 0]
    assert kp[KP.LEFT_SHOULDER, 1] > 0 > kp[KP.RIGHT_SHOULDER, 1]  # the person's left is +y


def test_standing_sway_is_small_and_walking_moves_the_limbs():
    still = standing(1.72)
    swayed = body_keypoints(np.array([1.72]), np.zeros(1), np.zeros(1), np.array([[0.012, 0.012]]))[0]
    assert 0.0 < np.abs(swayed - still).max() < 0.03
    assert np.abs(walking(np.array([0.0]), 1.72)[0] - still).max() > 0.2


@pytest.mark.parametrize("speed, expected", [(1.0, 1.29), (1.4, 1.43), (1.6, 1.50)])
def test_stride_length(speed, expected):
    assert stride_length(np.array([1.72]), np.array([speed]))[0] == pytest.approx(expected, abs=0.01)


@pytest.mark.parametrize("heading, forward", [(0.0, (1, 0)), (np.pi / 2, (0, 1)), (np.pi, (-1, 0))])
def test_world_keypoints_turn_to_the_heading_and_stand_on_the_ground_point(heading, forward):
    body = standing(1.8)[None]
    ground = np.array([[10.0, -4.0, 2.5]])
    kp = world_keypoints(ground, np.array([heading]), body)[0]
    nose_offset = kp[KP.NOSE, :2] - 0.5 * (kp[KP.LEFT_EAR, :2] + kp[KP.RIGHT_EAR, :2])
    assert np.dot(nose_offset / np.linalg.norm(nose_offset), forward) == pytest.approx(1.0, abs=1e-9)
    assert kp[KP.LEFT_ANKLE, 2] == pytest.approx(2.5 + 0.046 * 1.8)
