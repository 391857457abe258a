"""The body template: proportions, left/right symmetry, and the walker standing on it."""

import numpy as np
import pytest

from pedenv.body import STANDING, standing_body, world_keypoints
from pedenv.skeleton import CocoKeypoint as K
from pedenv.synthetic.walker import body_keypoints

PAIRS = [(K.LEFT_EYE, K.RIGHT_EYE), (K.LEFT_EAR, K.RIGHT_EAR), (K.LEFT_SHOULDER, K.RIGHT_SHOULDER),
         (K.LEFT_ELBOW, K.RIGHT_ELBOW), (K.LEFT_WRIST, K.RIGHT_WRIST), (K.LEFT_HIP, K.RIGHT_HIP),
         (K.LEFT_KNEE, K.RIGHT_KNEE), (K.LEFT_ANKLE, K.RIGHT_ANKLE)]


def test_template_is_mirror_symmetric_with_left_on_plus_y():
    for left, right in PAIRS:
        np.testing.assert_array_equal(STANDING[left] * [1, -1, 1], STANDING[right])
        assert STANDING[left, 1] > 0
    assert STANDING[K.NOSE, 1] == 0.0


def test_template_heights_hand_checked():
    # shares of body height; elbow and wrist hang straight: 0.818 - 0.186 and - 0.146 more
    assert STANDING[
        [K.NOSE, K.LEFT_EYE, K.LEFT_EAR, K.LEFT_SHOULDER, K.LEFT_HIP, K.LEFT_KNEE, K.LEFT_ANKLE], 2
    ].tolist() == [0.920, 0.933, 0.915, 0.818, 0.530, 0.285, 0.046]
    assert STANDING[K.LEFT_ELBOW, 2] == pytest.approx(0.632) and STANDING[K.LEFT_WRIST, 2] == pytest.approx(0.486)
    with pytest.raises(ValueError):
        STANDING[0, 0] = 1.0  # read-only: no caller can change everyone's person


def test_standing_body_scales_and_is_placed_facing_its_heading():
    body = standing_body([1.5, 2.0])
    assert body.shape == (2, 17, 3)
    assert body[1, K.LEFT_ANKLE, 2] == pytest.approx(0.046 * 2.0)
    # facing -x (heading pi): the nose is nearer -x than the ears, the left side at -y
    kp = world_keypoints(np.array([[10.0, 2.0, 0.5]]), np.array([np.pi]), body[:1])[0]
    assert kp[K.NOSE, 0] == pytest.approx(10.0 - 0.052 * 1.5) and kp[K.LEFT_HIP, 1] == pytest.approx(2.0 - 0.058 * 1.5)
    assert kp[K.LEFT_ANKLE, 2] == pytest.approx(0.5 + 0.046 * 1.5)


def test_the_walker_standing_still_is_the_template_but_for_its_arms():
    h = np.array([1.6, 1.9])
    walker = body_keypoints(h, phase=np.zeros(2), gait=np.zeros(2), sway=np.zeros((2, 2)))
    not_arms = [k for k in K if k not in (K.LEFT_ELBOW, K.RIGHT_ELBOW, K.LEFT_WRIST, K.RIGHT_WRIST)]
    np.testing.assert_allclose(walker[:, not_arms], standing_body(h)[:, not_arms], atol=1e-12)
    # its arms hang slightly abducted and bent: elbows within 3 cm of the template's
    arms = [K.LEFT_ELBOW, K.RIGHT_ELBOW]
    assert np.abs(walker[:, arms] - standing_body(h)[:, arms]).max() < 0.03
