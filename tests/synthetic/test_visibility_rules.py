"""Visibility rules on hand-placed standing people seen by the paper's camera from the origin."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.body import world_keypoints
from pedenv.records import Camera, EgoPose
from pedenv.synthetic.visibility import VisibilityRules, box_coverage, visible_pedestrians
from pedenv.synthetic.walker import body_keypoints

CAMERA = Camera.from_fov(1600, 900, 64.5, height_m=1.5)


DEFAULT_RULES = VisibilityRules()


def see(xy, heights=None, rules=DEFAULT_RULES):
    xy = np.asarray(xy, float).reshape(-1, 2)
    n = len(xy)
    heights = np.full(n, 1.75) if heights is None else np.asarray(heights, float)
    ground = np.column_stack([xy, np.zeros(n)])
    body = body_keypoints(heights, np.zeros(n), np.zeros(n), np.zeros((n, 2)))
    kp3d = world_keypoints(ground, np.full(n, np.pi), body)  # facing the camera
    cam_to_world = EgoPose.from_xy_yaw(0, 0, 0).matrix @ CAMERA.cam_to_vehicle
    return visible_pedestrians(kp3d, ground, CAMERA, cam_to_world, rules)


@pytest.mark.parametrize("xy, kept, why", [
    ((20.0, 0.0), True, "in plain view"),
    ((-20.0, 0.0), False, "behind the camera"),
    ((20.0, 30.0), False, "outside the field of view"),
    ((3.0, 0.0), False, "nearer than 5 m"),
    ((120.0, 0.0), True, "far but 16.4 px tall"),
    ((140.0, 0.0), False, "14.1 px tall, too small"),
    ((149.0, 60.0), False, "outside the field of view far away"),
    ((160.0, 0.0), False, "beyond 150 m"),
])
def test_single_person(xy, kept, why):
    assert bool(see([xy]).keep[0]) is kept, why


def test_pixel_height_is_the_keypoint_extent():
    # ankles (0.046 H) to eyes (0.933 H) of a 1.75 m person at 120 m: 1259.3 * 1.552 / 120 = 16.3 px
    v = see([(120.0, 0.0)])
    assert np.ptp(v.keypoints[0, :, 1]) == pytest.approx(16.3, abs=0.2)
    assert not see([(120.0, 0.0)], rules=VisibilityRules(min_height_px=20)).keep[0]


def test_person_behind_a_nearer_one_is_hidden_and_reappears_beside_it():
    hidden = see([(10.0, 0.0), (14.0, 0.0)])
    assert hidden.keep.tolist() == [True, False]
    beside = see([(10.0, 0.0), (14.0, 2.5)])
    assert beside.keep.tolist() == [True, True]
    # the nearer one is never hidden by the farther one
    assert see([(14.0, 0.0), (10.0, 0.0)]).keep.tolist() == [False, True]


def test_half_covered_person_keypoints_behind_the_occluder_are_not_visible():
    v = see([(10.0, 0.0), (14.0, 0.4)])  # a third of the far box is covered: it stays
    assert v.keep.tolist() == [True, True]
    assert box_coverage(v.boxes[1:], v.boxes[:1], np.array([[True]]))[0] == pytest.approx(1 / 3, abs=0.07)
    behind = v.keypoints[1, :, 0] >= v.boxes[0, 0]
    assert behind.any() and not v.visible[1, behind].any() and v.visible[1, ~behind].all()


def test_partly_outside_image_keypoints_are_marked_not_visible():
    # near the left border: some keypoints leave the image, most stay in
    v = see([(9.0, 5.45)])
    inside = (v.keypoints[0, :, 0] >= 0) & (v.keypoints[0, :, 0] < 1600)
    assert v.keep[0] and 0 < (~inside).sum() <= 6
    assert np.array_equal(v.visible[0], inside)
    assert v.boxes[0, 0] == 0.0  # the box is clipped to the image


def test_box_coverage_by_hand():
    boxes = np.array([[0.0, 0.0, 60.0, 60.0]])
    occluders = np.array([[0.0, 0.0, 30.0, 60.0], [0.0, 0.0, 60.0, 30.0], [100.0, 100.0, 120.0, 120.0]])
    # left half and top half cover 3/4 of the box; the third box is elsewhere
    assert box_coverage(boxes, occluders, np.array([[True, True, True]]))[0] == pytest.approx(0.75)
    assert box_coverage(boxes, occluders, np.array([[True, False, False]]))[0] == pytest.approx(0.5)
    assert box_coverage(boxes, occluders, np.array([[False, False, True]]))[0] == 0.0


@pytest.mark.parametrize("kwargs", [{"min_distance_m": 200.0}, {"min_height_px": -1}, {"max_occluded_fraction": 1.5},
                                    {"min_inside_fraction": -0.1}, {"min_depth_m": 0.0}])
def test_rules_reject_bad_thresholds(kwargs):
    with pytest.raises(ValueError):
        VisibilityRules(**kwargs)
