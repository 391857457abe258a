import numpy as np
import pytest

from pedenv.evaluation.matching import match_one_to_one, match_to_ground_truth, position_errors
from pedenv.evaluation.metrics import calibration, error_by_distance


def test_match_takes_nearest_in_world_among_overlapping_boxes():
    pred_boxes = np.array([[0, 0, 10, 10], [100, 0, 110, 10], [500, 0, 510, 10]], float)
    pred_xy = np.array([[10.0, 0.0], [30.0, 1.0], [5.0, 5.0]])
    gt_boxes = np.array([[5, 0, 15, 10], [2, 0, 12, 10], [105, 0, 115, 10]], float)
    gt_xy = np.array([[20.0, 0.0], [11.0, 0.0], [31.0, 1.0]])
    # first overlaps gt 0 and 1 (nearest: 1), second overlaps gt 2, third overlaps nothing
    assert match_to_ground_truth(pred_boxes, pred_xy, gt_boxes, gt_xy).tolist() == [1, 2, -1]


def test_one_to_one_pairs_each_estimate_with_its_own_person():
    # two people side by side; the estimate of the left one lies nearer the right one in x-y
    gt_boxes = np.array([[0, 0, 40, 100], [30, 0, 70, 100], [300, 0, 340, 100]], float)
    gt_xy = np.array([[20.0, 0.0], [20.0, -0.6]])
    pred_boxes = np.array([[1, 0, 41, 100], [29, 2, 69, 100], [150, 0, 190, 100], [305, 40, 345, 100]], float)
    pred_xy = np.array([[20.9, -0.5], [20.0, -0.6], [40.0, 0.0], [30.0, 3.0]])
    assert match_to_ground_truth(pred_boxes[:2], pred_xy[:2], gt_boxes[:2], gt_xy).tolist() == [1, 1]
    # the third overlaps nobody; the fourth overlaps person 2 at IoU 0.49, below 0.5
    assert match_one_to_one(pred_boxes, gt_boxes).tolist() == [0, 1, -1, -1]
    assert match_one_to_one(pred_boxes, gt_boxes, min_iou=0.3).tolist() == [0, 1, -1, 2]
    assert match_one_to_one(np.zeros((0, 4)), gt_boxes).tolist() == []
    assert match_one_to_one(pred_boxes, np.zeros((0, 4))).tolist() == [-1, -1, -1, -1]


def test_errors_hand_checked():
    abs_err, rel, dist = position_errors(np.array([[13.0, 4.0]]), np.array([[10.0, 0.0]]), np.array([0.0, 0.0]))
    assert abs_err[0] == pytest.approx(5.0) and dist[0] == pytest.approx(10.0) and rel[0] == pytest.approx(50.0)


def test_error_by_distance_bins_and_calibration():
    rows = error_by_distance(np.array([1.2, 1.8, 5.5]), np.array([1.0, 3.0, 2.0]), np.array([10.0, 20.0, 5.0]))
    assert rows == [{"distance_m": 1.0, "abs_error_m": 2.0, "rel_error_pct": 15.0, "count": 2},
                    {"distance_m": 5.0, "abs_error_m": 2.0, "rel_error_pct": 5.0, "count": 1}]
    c = calibration(np.array([0.5, 1.5, 2.5, 0.9]))
    assert c == pytest.approx({"within_1sigma": 0.5, "within_2sigma": 0.75,
                               "mean_nees": (0.25 + 2.25 + 6.25 + 0.81) / 4})
    assert np.isnan(calibration(np.array([np.nan]))["mean_nees"])
