"""The body template: proportions, left/right symmetry, and the walker standing on it."""

import numpy as np
import pytest

from pedenv.body import STANDING, standing_body, world_keypoints
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic.walker import body_keypoints

PAIRS = [(KP.LEFT_EYE, KP.RIGHT_EYE), (KP.LEFT_EAR, KP.RIGHT_EAR), (KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER),
         (KP.LEFT_ELBOW, KP.RIGHT_ELBOW), (KP.LEFT_WRIST, KP.RIGHT_WRIST), (KP.LEFT_HIP, KP.RIGHT_HIP),
         (KP.LEFT_KNEE, KP.RIGHT_KNEE), (KP.LEFT_ANKLE, KP.RIGHT_ANKLE)]


def test_template_is_mirror_symmetric_with_left_on_plus_y():
    for left, right in PAIRS:
        np.testing.assert_array_equal(STANDING[left] * [1, -1, 1], STANDING[right])
        assert STANDING[left, 1] > 0
    assert STANDING[KP.NOSE, 1] == 0.0


def test_template_heights_hand_checked():
    # shares of body height; elbow and wrist hang straight: 0.818 - 0.186 and - 0.146 more
    assert STANDING[
        [KP.NOSE, KP.LEFT_EYE, KP.LEFT_EAR, KP.LEFT_SHOULDER, KP.LEFT_HIP, KP.LEFT_KNEE, KP.LEFT_ANKLE], 2
    ].tolist() == [0.920, 0.933, 0.915, 0.818, 0.530, 0.285, 0.046]
    assert STANDING[KP.LEFT_ELBOW, 2] == pytest.approx(0.632) and STANDING[KP.LEFT_WRIST, 2] == pytest.approx(0.486)
    with pytest.raises(ValueError):
        STANDING[0, 0] = 1.0  # read-only: no caller can change everyone's person


def test_standing_body_scales_and_is_placed_facing_its_heading():
    body = standing_body([1.5, 2.0])
    assert body.shape == (2, 17, 3)
    assert body[1, KP.LEFT_ANKLE, 2] == pytest.approx(0.046 * 2.0)
    # facing -x (heading pi): the nose is nearer -x than the ears, the left side at -y
    kp = world_keypoints(np.array([[10.0, 2.0, 0.5]]), np.array([np.pi]), body[:1])[0]
    assert kp[KP.NOSE, 0] == pytest.approx(10.0 - 0.052 * 1.5) and \
        kp[KP.LEFT_HIP, 1] == pytest.approx(2.0 - 0.058 * 1.5)
    assert kp[KP.LEFT_ANKLE, 2] == pytest.approx(0.5 + 0.046 * 1.5)


def test_the_walker_standing_still_is_the_template_but_for_its_arms():
    h = np.array([1.6, 1.9])
    walker = body_keypoints(h, phase=np.zeros(2), gait=np.zeros(2), sway=np.zeros((2, 2)))
    not_arms = [k for k in KP if k not in (KP.LEFT_ELBOW, KP.RIGHT_ELBOW, KP.LEFT_WRIST, KP.RIGHT_WRIST)]
    np.testing.assert_allclose(walker[:, not_arms], standing_body(h)[:, not_arms], atol=1e-12)
    # its arms hang slightly abducted and bent: elbows within 3 cm of the template's
    arms = [KP.LEFT_ELBOW, KP.RIGHT_ELBOW]
    assert np.abs(walker[:, arms] - standing_body(h)[:, arms]).max() < 0.03
