"""The skeleton cue and the walking direction pin the body's yaw on constructed people."""

import numpy as np
import pytest
from tests.behaviour.people import seen

from pedenv.behaviour import heading_filter as hf
from pedenv.behaviour.config import BehaviourConfig
from pedenv.behaviour.orientation import motion_likelihood, skeleton_cue, skeleton_likelihood
from pedenv.geometry import wrap_angle

CFG = BehaviourConfig(enabled=True)
CELLS = hf.cell_centres(CFG.orientation_bins)


def _one_frame(xy, heading, confidences=None):
    rays, conf, feet, origin, focal = seen(xy, heading)
    cue = skeleton_cue(rays, conf if confidences is None else confidences, feet, origin, focal)
    p = hf.update(hf.uniform(len(feet), len(CELLS)), skeleton_likelihood(cue, CELLS))
    return cue, hf.summary(p, np.radians(CFG.available_std_deg))


@pytest.mark.parametrize("name, heading", [
    ("towards the camera", np.pi), ("away from the camera", 0.0),
    ("across, to the left", np.pi / 2), ("across, to the right", -np.pi / 2),
    ("oblique", 2.3),
])
def test_one_frame_of_a_skeleton_gives_the_yaw(name, heading):
    cue, (yaw, std, available) = _one_frame([12.0, 1.0], heading)
    assert abs(wrap_angle(yaw[0] - heading)) < np.radians(12), name
    assert np.isfinite(std).all() and available[0] >= hf.SIGN_UNKNOWN


def test_width_and_face_ratios_are_cos_and_sin_of_the_angle_to_the_camera():
    # a person straight ahead facing the camera: cos(a) = 1; facing to the image's right: sin(a) = 1
    cue, _ = _one_frame([[10.0, 0.0], [10.0, 0.0]], [np.pi, -np.pi / 2])
    assert cue.width[0] == pytest.approx(1.0, abs=0.05) and abs(cue.width[1]) < 0.05
    assert abs(cue.face[0]) < 0.05 and cue.face[1] == pytest.approx(1.0, abs=0.1)


def test_no_shoulders_or_hips_no_face_means_unavailable():
    conf = np.zeros((1, 17))
    cue, (yaw, std, available) = _one_frame([12.0, 0.0], 0.3, confidences=conf)
    assert not cue.width_ok[0] and not cue.face_ok[0]
    assert available[0] == hf.UNAVAILABLE and std[0] > np.radians(90) and np.isfinite(yaw[0])


def test_walking_direction_is_a_cue_only_when_the_speed_is_clearly_above_zero():
    v = np.array([[1.4, 0.0], [0.1, 0.0], [1.4, 0.0]])
    cov = np.array([np.eye(2) * 0.01, np.eye(2) * 0.01, np.eye(2) * 1.0])
    like, used = motion_likelihood(v, cov, CELLS)
    assert used.tolist() == [True, False, False]
    assert abs(CELLS[like[0].argmax()]) < np.radians(5) and np.ptp(like[1]) == 0
