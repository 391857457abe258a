"""Identities that hold (beyond the paper): hand-made scenes for the two-stage association,
the projected Kalman gate and the memory of lost tracks."""

from functools import partial

import numpy as np
import pytest

from pedenv.config import TrackingConfig
from pedenv.tracking.projection import CameraView, foot_points, pixel_distances
from pedenv.tracking.recall import EXPECTED_DISTANCE_2DOF, camera_disagrees, ground_terms
from pedenv.tracking.tracker import Tracker

F, CX, CY, W, H = 1000.0, 640.0, 360.0, 1280, 720
CAM_HEIGHT_M, PERSON_M = 1.5, 1.7
#: optical camera (x right, y down, z forward) -> world (x forward, y left, z up), 1.5 m up
CAM_TO_WORLD = np.array([[0.0, 0.0, 1.0, 0.0], [-1.0, 0.0, 0.0, 0.0], [0.0, -1.0, 0.0, CAM_HEIGHT_M],
                         [0.0, 0.0, 0.0, 1.0]])
FUSED = {"max_height_ratio": 1.5, "predict_motion": True, "ground_gate": 4.0, "memory_s": 2.0}


def view(t: float) -> CameraView:
    return CameraView(np.array([[F, 0, CX], [0, F, CY], [0, 0, 1.0]]), CAM_TO_WORLD, np.linalg.inv(CAM_TO_WORLD),
                      np.array([0.0, 0.0, 1.0]), 0.0, H, t)


def box(x: float, y: float, du: float = 0.0) -> np.ndarray:
    """The box (4,) pixels of a person standing at world (x, y), moved du pixels sideways."""
    u, v, h = CX - F * y / x + du, CY + F * CAM_HEIGHT_M / x, F * PERSON_M / x
    return np.array([u - 0.2 * h, v - h, u + 0.2 * h, v])


def set_filters(tracker: Tracker, states: dict[int, tuple[float, float, float, float]], std_m: float = 0.1) -> None:
    """Give each track id its Kalman state ``(x, vx, y, vy)``, as the model's filter would."""
    f = tracker.table.filter
    for row, track_id in enumerate(tracker.ids):
        if track_id in states:
            f.x[row] = states[track_id]
            f.P[row] = np.diag([std_m**2, 0.1, std_m**2, 0.1])
            f.started[row] = True


def test_projection_puts_a_standing_person_on_their_foot_point():
    xy = np.array([[10.0, 1.0], [20.0, -2.0]])
    d2 = pixel_distances(view(0.0), np.stack([box(10, 1), box(20, -2)]), xy, np.tile(0.01 * np.eye(2), (2, 1, 1)))
    assert np.diag(d2) == pytest.approx([0.0, 0.0], abs=1e-9)
    assert d2[0, 1] > 100 and d2[1, 0] > 100
    np.testing.assert_allclose(foot_points(box(10, 1)[None]), [[CX - 100.0, CY + 150.0]])


def test_a_point_behind_the_camera_is_never_near():
    d2 = pixel_distances(view(0.0), box(10, 0)[None], np.array([[-5.0, 0.0]]), 0.01 * np.eye(2)[None])
    assert np.isinf(d2[0, 0])


@pytest.mark.parametrize("std_m, near", [(0.05, False), (0.4, None)])
def test_a_prediction_whose_spread_reaches_behind_the_camera_is_not_projected(std_m, near):
    """A track predicted 1.1 m ahead (a person the car has nearly passed): with 5 cm spread it
    projects far below a detection 80 m away; with 0.4 m its spread reaches behind the camera,
    the linearized projection (thousands of pixels wide) would take that detection in, so the
    distance is infinite: no recall, and the ground gate abstains."""
    far = box(80.0, 0.5)[None]
    d2 = pixel_distances(view(0.0), far, np.array([[1.1, 0.3]]), std_m**2 * np.eye(2)[None])
    if near is None:
        assert np.isinf(d2[0, 0])
    else:
        assert np.isfinite(d2[0, 0]) and d2[0, 0] > 20
    tracker = Tracker(TrackingConfig(**FUSED))
    tracker.update(box(5.0, 0.3)[None], view=view(0.0))
    f = tracker.table.filter
    f.x[0], f.P[0], f.started[0] = (1.1, 0.0, 0.3, 0.0), np.diag([std_m**2, 0.1, std_m**2, 0.1]), True
    allowed, cost = ground_terms(far, f, view(0.1), tracker.config)
    assert allowed[0, 0] == (near is None)
    if near is None:
        assert cost[0, 0] == pytest.approx(EXPECTED_DISTANCE_2DOF / 4.0)  # abstains: the expected cost


@pytest.mark.parametrize("gate, swapped", [(0.0, True), (4.0, False)])
def test_side_by_side_walkers_keep_their_ids_with_the_projected_prediction(gate, swapped):
    """Two people 0.6 m apart at 10 m walk sideways together at 1.5 m/s; both are missed
    for two frames (a passing car), so their stored boxes are 0.45 m behind: by the boxes
    alone the first walker's detection lies nearest the second's track. The Kalman
    prediction, projected into the image, holds their ids."""
    tracker = Tracker(TrackingConfig(ground_gate=gate))
    tracker.update(np.stack([box(10, 0.3), box(10, -0.3)]), view=view(0.0))
    for t in (0.1, 0.2):
        tracker.update(np.zeros((0, 4)), view=view(t))
    set_filters(tracker, {1: (10, 0, 0.3 - 0.45, -1.5), 2: (10, 0, -0.3 - 0.45, -1.5)})  # the model's prediction
    step = tracker.update(np.stack([box(10, 0.3 - 0.45), box(10, -0.3 - 0.45)]), view=view(0.3))
    ids = tracker.ids[step.detection_rows]
    if swapped:
        assert ids[0] == 2
    else:
        assert list(ids) == [1, 2]


@pytest.mark.parametrize("config, holds", [
    (TrackingConfig(), False), (TrackingConfig(predict_motion=True, max_height_ratio=1.5), False),
    (TrackingConfig(**FUSED), True)])
def test_crossing_walkers_keep_their_ids(config, holds):
    """Two people at 9 and 9.2 m walk across each other at 1.4 m/s, 10 Hz, box edges noisy
    by 8 % of the height: the boxes alone (with or without image motion) swap them."""
    rng = np.random.default_rng(3)
    tracker = Tracker(config)
    first, swapped = None, 0
    for k in range(30):
        t = 0.1 * k
        people = [(9.0, -2.0 + 1.4 * t, 1.4), (9.2, 2.0 - 1.4 * t, -1.4)]
        boxes = np.stack([box(x, y) for x, y, _ in people])
        boxes += rng.normal(0, 0.08, boxes.shape) * (boxes[:, 3:] - boxes[:, 1:2])
        set_filters(tracker, {i + 1: (x, 0.0, y, vy) for i, (x, y, vy) in enumerate(people)})
        step = tracker.update(boxes, view=view(t))
        ids = list(tracker.ids[step.detection_rows])
        first = first or ids
        swapped += ids != first
    assert (swapped == 0) == holds


@pytest.mark.parametrize("memory_s, hidden, same_id", [(2.0, 8, True), (0.0, 8, False), (2.0, 25, False)])
def test_a_person_hidden_for_n_frames_gets_their_id_back(memory_s, hidden, same_id):
    tracker = Tracker(TrackingConfig(max_misses=3, memory_s=memory_s))
    t = 0.0
    for _ in range(3):
        tracker.update(box(12, 1.0)[None], view=view(t))
        set_filters(tracker, {1: (12, 0, 1.0, 0)})
        t += 0.1
    for _ in range(hidden):  # hidden behind a van
        step = tracker.update(np.zeros((0, 4)), view=view(t))
        t += 0.1
    assert (len(tracker) == 1) == (memory_s > 0 and hidden * 0.1 <= memory_s + 0.3)
    step = tracker.update(np.stack([box(12.1, 1.05), box(15, -3.0)]), view=view(t))
    ids = tracker.ids[step.detection_rows]
    assert (ids[0] == 1) == same_id
    assert ids[1] != 1  # someone elsewhere never takes the remembered id


def test_low_score_detections_continue_tracks_but_never_start_one():
    tracker = Tracker(TrackingConfig(low_score_threshold=0.1))
    a, b, c = box(10, 1.0), box(15, -2.0), box(20, 4.0)
    tracker.update(np.stack([a, b]), scores=np.array([0.9, 0.8]))
    step = tracker.update(np.stack([a, b + 2.0, c]), scores=np.array([0.15, 0.05, 0.2]))
    rows = step.detection_rows
    assert tracker.ids[rows[0]] == 1 and tracker.misses[rows[0]] == 0  # occluded person kept by a weak detection
    assert rows[1] == -1 and rows[2] == -1  # below the band; no track started by a weak one
    assert sorted(tracker.ids) == [1, 2] and tracker.misses[tracker.ids == 2] == 1


def test_the_papers_tracker_ignores_scores():
    tracker = Tracker(TrackingConfig())
    tracker.update(box(10, 1.0)[None], scores=np.array([0.9]))
    step = tracker.update(np.stack([box(10, 1.0), box(20, 4.0)]), scores=np.array([0.05, 0.05]))
    assert list(tracker.ids[step.detection_rows]) == [1, 2]


def test_lost_rows_are_carried_with_every_column():
    tracker = Tracker(TrackingConfig(max_misses=1, memory_s=1.0))
    tracker.update(np.stack([box(10, 1.0), box(12, -1.0)]), view=view(0.0))
    set_filters(tracker, {1: (10, 0, 1.0, 0), 2: (12, 0, -1.0, 0)})
    tracker.update(box(12, -1.0)[None], view=view(0.1))
    tr, f = tracker.table.tracks, tracker.table.filter
    assert list(tr.ids) == [2, 1] and list(tr.lost) == [False, True]
    assert f.x[1] == pytest.approx([10, 0, 1.0, 0]) and tr.last_seen[1] == 0.0
    step = tracker.update(box(12, -1.0)[None], view=view(1.2))  # memory ran out
    assert list(tracker.ids) == [2] and list(step.dropped_ids) == [1]


@pytest.mark.parametrize("field, value", [
    ("low_score_threshold", 0.3), ("low_score_threshold", -0.1), ("ground_gate", -1.0), ("memory_s", -1.0),
    ("memory_s", 100.0)])
def test_identity_fields_are_checked(field, value):
    with pytest.raises(ValueError, match=f"tracking.{field}"):
        TrackingConfig(**{field: value})


def test_the_low_band_reaches_the_tracker_only_when_it_is_on():
    from pedenv.detection import backend_options

    assert TrackingConfig().pose_score_threshold is None
    assert TrackingConfig(low_score_threshold=0.1).pose_score_threshold == 0.1
    assert "score_threshold" not in backend_options("onnx")  # the paper's input: the backend's own 0.25
    assert backend_options("onnx", score_threshold=0.1)["score_threshold"] == 0.1
    assert backend_options("ultralytics", score_threshold=0.1)["score_threshold"] == 0.1


def _three_walkers(tracker: Tracker, states: dict, t: float = 0.1):
    """Three people 2 m apart at 10-14 m, seen at t = 0, then again at ``t`` in place; their
    filters hold ``states`` (what the model's filter made of them)."""
    people = np.stack([box(10, 2.0), box(12, 0.0), box(14, -2.0)])
    tracker.update(people, view=view(0.0))
    set_filters(tracker, states)
    return tracker.update(people, view=view(t))


def test_a_camera_the_image_contradicts_leaves_the_boxes_to_decide(monkeypatch):
    """The filters, fed through a wrong calibration, put everyone 2.5x farther than where
    their foot points project; the ground gate would split every track. The unambiguous
    box matches disagree with the camera, so the gate abstains and all keep their ids."""
    wrong = {1: (25, 0, 5.0, 0), 2: (30, 0, 0.0, 0), 3: (35, 0, -5.0, 0)}
    right = {1: (10, 0, 2.0, 0), 2: (12, 0, 0.0, 0), 3: (14, 0, -2.0, 0)}
    for states, check, kept in ((right, 0.5, True), (wrong, 0.5, True), (wrong, 1.0, False)):
        monkeypatch.setattr("pedenv.tracking.tracker.camera_disagrees", partial(camera_disagrees, max_share=check))
        tracker = Tracker(TrackingConfig(**FUSED))
        step = _three_walkers(tracker, states)
        assert (list(tracker.ids[step.detection_rows]) == [1, 2, 3]) == kept
        assert tracker.camera_trusted == (states is right or check == 1.0)


def test_the_camera_check_needs_three_unambiguous_matches():
    boxes = np.stack([box(10, 2.0), box(12, 0.0), box(14, -2.0)])
    outside = np.zeros((3, 3), bool)
    rows = np.arange(3)
    assert camera_disagrees(outside, boxes, boxes, rows, max_share=0.5)
    assert not camera_disagrees(outside[:2], boxes[:2], boxes, rows, max_share=0.5)
    assert not camera_disagrees(np.eye(3, dtype=bool), boxes, boxes, rows, max_share=0.5)
    assert not camera_disagrees(outside, boxes, boxes, rows, max_share=1.0)
