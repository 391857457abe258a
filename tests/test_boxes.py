"""IoU, generalized IoU and NMS of image boxes, with hand-worked numbers."""

import numpy as np
import pytest

from pedenv.boxes import containment_matrix, giou_matrix, greedy_match, iou_matrix, nms


@pytest.mark.parametrize("a, b, expected", [
    ([0, 0, 2, 2], [0, 0, 2, 2], 1.0),
    ([0, 0, 2, 2], [1, 1, 3, 3], 1 / 7),                  # overlap 1x1, union 4 + 4 - 1
    ([0, 0, 10, 10], [5, 0, 15, 10], 50 / 150),
    ([0, 0, 4, 2], [1, 0, 2, 2], 2 / 8),                  # b inside a: its area over a's
    ([0, 0, 1, 1], [1, 0, 2, 1], 0.0),                    # touching edges: no area in common
    ([0, 0, 10, 10], [20, 20, 30, 30], 0.0),
    ([3, 3, 3, 3], [3, 3, 3, 3], 0.0),                    # zero-area boxes: no union, 0 not NaN
])
def test_iou_hand_checked(a, b, expected):
    assert iou_matrix(np.array([a], float), np.array([b], float))[0, 0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("a, b, expected", [
    ([0, 0, 2, 2], [0, 0, 2, 2], 1.0),
    ([0, 0, 2, 2], [1, 1, 3, 3], 1 / 7 - 2 / 9),          # IoU 1/7, hull 9, union 7
    ([0, 0, 1, 1], [2, 0, 3, 1], -1 / 3),                 # disjoint: hull 3, union 2
    ([0, 0, 1, 1], [1.5, 0, 2.5, 1], -0.2),               # hull 2.5, union 2
    ([0, 0, 1, 1], [100, 100, 101, 101], 2 / (101 * 101) - 1),
    ([3, 3, 3, 3], [3, 3, 3, 3], -1.0),                   # zero-area boxes: no IoU, no hull, finite
])
def test_giou_hand_checked(a, b, expected):
    assert giou_matrix(np.array([a], float), np.array([b], float))[0, 0] == pytest.approx(expected, abs=1e-12)


def test_iou_and_giou_are_symmetric_and_vectorized():
    rng = np.random.default_rng(1)
    lo = rng.uniform(0, 100, (6, 2))
    boxes = np.hstack([lo, lo + rng.uniform(1, 30, (6, 2))])
    for f, low in ((iou_matrix, 0.0), (giou_matrix, -1.0)):
        m = f(boxes, boxes[:4])
        assert m.shape == (6, 4)
        np.testing.assert_allclose(m[:4, :4], m[:4, :4].T)
        np.testing.assert_allclose(np.diag(m[:4, :4]), 1.0)
        assert np.all(m >= low) and np.all(m <= 1)
        # each entry is the pair's own value
        assert m[5, 2] == f(boxes[5:6], boxes[2:3])[0, 0]
    assert (giou_matrix(boxes, boxes[:4]) <= iou_matrix(boxes, boxes[:4]) + 1e-12).all()


@pytest.mark.parametrize("n, m", [(0, 3), (2, 0), (0, 0)])
def test_empty_inputs_give_empty_matrices(n, m):
    for f in (iou_matrix, giou_matrix):
        assert f(np.zeros((n, 4)), np.zeros((m, 4))).shape == (n, m)


def test_nms_keeps_best_and_drops_overlaps():
    boxes = np.array([[1.0, 0, 11, 10], [0, 0, 10, 10], [5, 0, 15, 10], [40, 40, 50, 50]])
    scores = np.array([0.8, 0.9, 0.7, 0.6])
    # box 0 overlaps box 1 by IoU 90/110 = 0.82 > 0.7: dropped; box 2 overlaps box 1 by 50/150 = 1/3: kept
    np.testing.assert_array_equal(nms(boxes, scores, 0.7), [1, 2, 3])
    # with a threshold of 0.3 box 2 (IoU 1/3 with box 1) goes too
    np.testing.assert_array_equal(nms(boxes, scores, 0.3), [1, 3])
    np.testing.assert_array_equal(nms(boxes, scores, 0.7, max_detections=2), [1, 2])
    assert nms(np.zeros((0, 4)), np.zeros(0), 0.7).shape == (0,)


def test_nms_drops_only_against_kept_boxes():
    # 1 suppresses 0 (IoU 90/110); 0 would have suppressed 2 (IoU 80/120 = 0.67) but is gone,
    # and 2 overlaps 1 by 70/130 = 0.54 only, so 2 stays
    boxes = np.array([[1.0, 0, 11, 10], [0, 0, 10, 10], [3, 0, 13, 10]])
    np.testing.assert_array_equal(nms(boxes, np.array([0.8, 0.9, 0.7]), 0.6), [1, 2])
    # equal scores keep their input order
    np.testing.assert_array_equal(nms(boxes[[1, 2]], np.array([0.5, 0.5]), 0.9), [0, 1])


@pytest.mark.parametrize("a, b, expected", [
    ([0, 0, 10, 10], [0, 0, 20, 20], 1.0),    # a inside b
    ([0, 0, 20, 20], [0, 0, 10, 10], 0.25),   # a quarter of a lies in b
    ([0, 0, 10, 10], [5, 0, 15, 10], 0.5),
    ([0, 0, 10, 10], [20, 20, 30, 30], 0.0),
])
def test_containment_is_the_share_of_the_first_box_inside_the_second(a, b, expected):
    assert containment_matrix(np.array([a], float), np.array([b], float))[0, 0] == pytest.approx(expected)


def test_greedy_match_lets_the_higher_score_take_the_shared_box_first():
    truth = np.array([[0, 0, 10, 20], [30, 0, 40, 20]], float)
    dets = np.array([[1, 0, 11, 20], [0, 0, 10, 20], [60, 0, 70, 20]], float)
    iou = iou_matrix(dets, truth)
    # detection 1 overlaps truth 0 exactly but scores lower than detection 0, which takes it
    assert greedy_match(iou, np.array([0.9, 0.8, 0.7]), 0.5) == [(0, 0)]
    assert greedy_match(iou, np.array([0.5, 0.8, 0.7]), 0.5) == [(1, 0)]
    assert greedy_match(np.zeros((2, 0)), np.array([0.9, 0.8])) == []
