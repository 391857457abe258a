"""Skeleton-aware merging of the detections of overlapping passes."""

import numpy as np
import pytest

from pedenv.detection.merge import keypoint_similarity, merge_detections
from pedenv.detection.passes import cut_by_inner_edge, spans_the_region
from pedenv.records import Detections

# A standing person 100 px tall, COCO-17, box (0, 0)-(40, 100) before shifting.
TEMPLATE = np.array([[20, 8], [22, 6], [18, 6], [25, 8], [15, 8], [30, 22], [10, 22], [34, 40], [6, 40],
                     [35, 55], [5, 55], [27, 55], [13, 55], [28, 77], [12, 77], [28, 98], [12, 98]], float)


def person(x: float, y: float, score: float, scale: float = 1.0, seen=slice(None)) -> Detections:
    kp = TEMPLATE * scale + [x, y]
    conf = np.zeros(17)
    conf[seen] = 0.9
    vis = kp[conf > 0]
    box = np.r_[vis.min(0) - 2, vis.max(0) + 2]
    return Detections(kp[None], conf[None], box[None], np.array([score]))


def test_same_person_from_two_passes_is_kept_once_with_the_whole_one():
    whole = person(100, 50, 0.6)
    again = person(101, 51, 0.8)
    merged = merge_detections([(whole, np.array([False])), (again, np.array([True]))])
    assert len(merged) == 1 and merged.scores[0] == pytest.approx(0.6)  # the uncut one wins despite its score


def test_a_half_person_cut_by_a_seam_is_dropped_in_favour_of_the_whole_one():
    whole = person(100, 50, 0.5)
    upper_half = person(100, 50, 0.9, seen=slice(0, 11))  # head and arms only: a box nested in the whole
    merged = merge_detections([(upper_half, np.array([True])), (whole, np.array([False]))])
    assert len(merged) == 1 and merged.boxes[0, 3] > 140


def test_a_cut_fragment_nested_in_a_whole_person_goes_even_if_its_keypoints_differ():
    whole = person(100, 50, 0.5, scale=1.6)
    fragment = person(130, 60, 0.9, scale=0.8)  # nested, other keypoints, but cut by a seam
    merged = merge_detections([(whole, np.array([False])), (fragment, np.array([True]))])
    assert len(merged) == 1 and merged.scores[0] == pytest.approx(0.5)


def test_two_people_one_behind_the_other_stay_two():
    front = person(100, 50, 0.9, scale=1.6)
    behind = person(112, 60, 0.8, scale=0.8)  # nested in the front box, different skeleton
    merged = merge_detections([(front, np.array([False])), (behind, np.array([False]))])
    assert len(merged) == 2


def test_people_side_by_side_stay_apart_and_empty_parts_are_fine():
    a, b = person(100, 50, 0.9), person(160, 50, 0.8)
    merged = merge_detections([(Detections.empty(), np.zeros(0, bool)), (a, np.array([False])), (b, np.array([True]))])
    assert len(merged) == 2
    assert len(merge_detections([])) == 0


def test_keypoint_similarity_is_one_for_equal_skeletons_and_falls_with_distance():
    d = person(0, 0, 1.0)
    same = keypoint_similarity(d.keypoints[0], d.confidences[0], d.keypoints, d.confidences, d.boxes[0], d.boxes, 0.3)
    far = person(30, 0, 1.0)
    moved = keypoint_similarity(d.keypoints[0], d.confidences[0], far.keypoints, far.confidences, d.boxes[0],
                                far.boxes, 0.3)
    assert same[0] == pytest.approx(1.0) and moved[0] < 0.1


def test_cut_flags_only_at_inner_edges():
    boxes = np.array([[0, 10, 50, 100], [300, 10, 398, 100], [150, 10, 200, 100]], float)
    cut = cut_by_inner_edge(boxes, (0, 0, 400, 300), (300, 1000), 4)
    assert cut.tolist() == [False, True, False]  # the left edge is the image's own


def test_a_box_spanning_the_band_from_edge_to_edge_is_a_fragment():
    band = (200, 200, 520, 306)  # a tile of the band, rows 200-306 of a 640x480 image
    boxes = np.array([[141, 200, 299, 305], [300, 230, 330, 300], [400, 200, 430, 260.0]])
    assert spans_the_region(boxes, band, (480, 640), 2).tolist() == [True, False, False]
