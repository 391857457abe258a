"""The own uncertainty of a box-bottom ground truth (:mod:`pedenv.evaluation.box_truth`, used by
benchmarks/static_cameras.py on MOT17): the slant of upright people under a camera looking down,
and a foot's length along the ray."""

import numpy as np
import pytest

from pedenv.geometry import invert_transform, project
from pedenv.synthetic.scenarios import static_camera

#: Thin upright people (feet to a 1.7 m head) standing at these ground points, vehicle frame, metres.
FEET = np.array([[6.0, 4.0, 0.0], [8.0, -3.0, 0.0], [12.0, 0.0, 0.0]])


def boxes_of(camera, feet: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(boxes (N, 4) px of the people standing at ``feet``, their feet's pixels (N, 2))."""
    ends = np.concatenate([feet, feet + [0.0, 0.0, 1.7]])
    px, _ = project(ends, camera.intrinsics, invert_transform(camera.cam_to_vehicle))
    foot, head = px[: len(feet)], px[len(feet):]
    return np.column_stack([np.minimum(foot, head), np.maximum(foot, head)]), foot


@pytest.mark.parametrize("pitch_deg, slanted", [(0.0, False), (20.0, True), (60.0, True)])
def test_the_feet_lie_on_the_line_from_the_vertical_vanishing_point(pitch_deg, slanted):
    from pedenv.evaluation.box_truth import slant_feet

    camera = static_camera(6.0, pitch_deg)
    boxes, foot = boxes_of(camera, FEET)
    found = slant_feet(camera, boxes)
    np.testing.assert_allclose(found, foot, atol=1e-6)  # a thin upright person: exactly its feet
    off_centre = np.abs(found[:, 0] - 0.5 * (boxes[:, 0] + boxes[:, 2]))
    assert (off_centre[:2] > 1.0).all() == slanted  # the people to the side are slanted when looking down


def test_truth_covariance_is_the_slant_and_a_foot_along_the_ray():
    from pedenv.datasets.ucmctrack import ground_points
    from pedenv.evaluation.box_truth import truth_covariances

    foot_var = (0.152 * 1.72) ** 2 / 12  # uniform over a foot's length: sigma 0.075 m
    level = static_camera(6.0, 0.0)
    boxes, _ = boxes_of(level, FEET)
    cov = truth_covariances(level, boxes, FEET[:, :2])
    along = FEET[:, :2] / np.linalg.norm(FEET[:, :2], axis=1, keepdims=True)
    np.testing.assert_allclose(cov, foot_var * along[:, :, None] * along[:, None, :], atol=1e-9)
    steep = static_camera(6.0, 60.0)
    boxes, _ = boxes_of(steep, FEET)
    bottom = np.column_stack([0.5 * (boxes[:, 0] + boxes[:, 2]), boxes[:, 3]])
    truth, _ = ground_points(steep, bottom)  # the box bottom's ground point: off the feet
    cov = truth_covariances(steep, boxes, truth[:, :2])
    d = FEET[:, :2] - truth[:, :2]
    assert np.linalg.norm(d[:2], axis=1).min() > 0.2  # people to the side: tens of centimetres
    np.testing.assert_allclose(np.trace(cov, axis1=1, axis2=2), (d**2).sum(1) + foot_var, rtol=1e-6)
