"""Yaw compensation (Eq. 1) with a turning ego, and the tracker's bookkeeping."""

import numpy as np
import pytest

from pedenv.config import Config, TrackingConfig
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import EgoPose
from pedenv.tracking.egomotion import shift_u, yaw_change, yaw_shift_pixels
from pedenv.tracking.table import carry_rows
from pedenv.tracking.tracker import Tracker

from standing_people import frame_with_people


def test_yaw_shift_hand_checked():
    # 2 deg of a 64.5 deg field of view on 1600 px: 49.61 px, to the right for a left turn
    assert yaw_shift_pixels(np.radians(2.0), np.radians(64.5), 1600) == pytest.approx(1600 * 2 / 64.5)
    assert yaw_change(np.radians(179), np.radians(-179)) == pytest.approx(np.radians(2))
    np.testing.assert_allclose(shift_u(np.array([[1.0, 2.0, 3.0, 4.0]]), 5.0), [[6.0, 2.0, 8.0, 4.0]])


def test_compensation_sign_with_a_left_turning_ego(camera):
    """A static person seen before and after a 3 deg left turn: compensated pixels line up."""
    person = [(25.0, 4.0)]
    a = frame_with_people(0, 0.0, EgoPose.from_xy_yaw(0, 0, 0.0), person)
    b = frame_with_people(1, 0.1, EgoPose.from_xy_yaw(0, 0, np.radians(3.0)), person)
    shift = yaw_shift_pixels(yaw_change(a.ego.yaw, b.ego.yaw), camera.hfov, camera.width)
    before, after = a.detections.boxes[0], b.detections.boxes[0]
    assert after[0] - before[0] == pytest.approx(shift, rel=0.1)  # the scene moves right by ~74 px
    assert abs(shift_u(before, shift)[0] - after[0]) < 8.0


@pytest.mark.parametrize("compensate, same_id", [(True, True), (False, False)])
def test_turning_ego_keeps_ids_only_with_compensation(compensate, same_id):
    """Ego turning at 40 deg/s past a far, thin pedestrian: 100 px per frame of yaw shift."""
    cfg = Config(method="paper", tracking=TrackingConfig(yaw_compensation=compensate))
    model = PedestrianEnvironmentModel(cfg)
    ids = []
    for i in range(6):
        yaw = np.radians(4.0) * i
        frame = frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(0, 0, yaw), [(60.0, 15.0)])
        ids.append(model.update(frame).pedestrians.track_ids.tolist())
    assert (len({tuple(x) for x in ids}) == 1) is same_id


def test_tracker_drops_after_three_misses_and_carries_rows():
    tr = Tracker(TrackingConfig(max_misses=3))
    box = np.array([[0, 0, 10, 20.0]])
    step = tr.update(box)
    assert tr.ids.tolist() == [1] and step.previous_rows.tolist() == [-1]
    for miss in (1, 2):
        step = tr.update(np.zeros((0, 4)))
        assert tr.ids.tolist() == [1] and tr.misses.tolist() == [miss]
    step = tr.update(np.zeros((0, 4)))
    assert tr.ids.tolist() == [] and step.dropped_ids.tolist() == [1]
    # a new detection gets a new id; reset restarts the counter
    tr.update(box)
    assert tr.ids.tolist() == [2]
    tr.reset()
    tr.update(box)
    assert tr.ids.tolist() == [1]


def test_tracker_row_mapping_matches_detections():
    tr = Tracker()
    a = np.array([[0, 0, 10, 20], [100, 0, 110, 20]], float)
    tr.update(a)
    b = np.array([[300, 0, 310, 20], [101, 0, 111, 20]], float)  # second matches track 2; first is new
    step = tr.update(b)
    assert tr.ids[step.detection_rows].tolist() == [3, 2]
    assert step.previous_rows.tolist() == [1, 0, -1]
    np.testing.assert_array_equal(carry_rows(np.array([10, 20]), step.previous_rows), [20, 10, 0])


def test_restart_gate_restarts_the_filter_after_an_identity_jump():
    """A track joined to a person 25 m farther (the paper's tracker allows it): the gated
    filter restarts there at once instead of crawling over."""
    from pedenv.config import KalmanConfig

    for gate, follows in ((0.0, False), (25.0, True)):
        model = PedestrianEnvironmentModel(Config(method="paper", kalman=KalmanConfig(restart_gate=gate)))
        for i in range(8):
            model.update(frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(1.0 * i, 0, 0), [(20.0, 0.0)]))
        frame = frame_with_people(8, 0.8, EgoPose.from_xy_yaw(8.0, 0, 0), [(45.0, 0.0)])
        state = model.update(frame)
        assert state.pedestrians.track_ids.tolist() == [1]
        assert bool(state.pedestrians.positions[0, 0] > 40.0) is follows


def test_bias_covariance_is_reported_but_not_filtered():
    """A per-person bias part of the measurement covariance stays in the reported covariance."""
    from dataclasses import replace as dc_replace

    from pedenv.localization.paper import PaperLocator

    class BiasedLocator(PaperLocator):
        def locate(self, geo, rows):
            m = super().locate(geo, rows)
            return dc_replace(m, bias_covariances=np.broadcast_to(4.0 * np.eye(2), m.covariances.shape).copy())

    paper = Config(method="paper")
    plain, biased = PedestrianEnvironmentModel(paper), PedestrianEnvironmentModel(paper, locator=BiasedLocator(paper))
    for i in range(20):
        frame = frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(1.0 * i, 0, 0), [(40.0, 3.0)])
        a, b = plain.update(frame).pedestrians, biased.update(frame).pedestrians
    np.testing.assert_allclose(a.positions, b.positions)  # the filter itself is unchanged
    np.testing.assert_allclose(b.covariances - a.covariances, [4.0 * np.eye(2)], atol=1e-9)


@pytest.mark.parametrize("predict, kept", [(False, False), (True, True)])
def test_motion_prediction_follows_a_fast_crossing_box(predict, kept):
    """An 8 px wide box moving 9 px per frame, then 16: a 16 px step leaves its old place
    (GIoU -1/3 < -0.3) but not the place predicted from its velocity."""
    tr = Tracker(TrackingConfig(predict_motion=predict))
    ids = []
    for u in (100.0, 109.0, 118.0, 127.0, 136.0, 145.0, 161.0, 177.0, 193.0):
        tr.update(np.array([[u, 100.0, u + 8.0, 130.0]]))
        ids.append(int(tr.ids[tr.misses == 0][0]))
    assert (len(set(ids)) == 1) is kept


def test_a_static_camera_gets_no_yaw_shift():
    """A static camera's ego does not move: poses that say it turned (jitter, a wrong file) shift nothing."""
    from dataclasses import replace

    from pedenv.records import Camera

    def static(frame):
        c = frame.camera
        return replace(frame, camera=Camera(c.intrinsics, c.width, c.height, c.cam_to_vehicle, "static"))

    a = frame_with_people(0, 0.0, EgoPose.from_xy_yaw(0, 0, 0.0), [(25.0, 4.0)])
    b = frame_with_people(1, 0.1, EgoPose.from_xy_yaw(0, 0, np.radians(3.0)), [(25.0, 4.0)])
    for make, moved in ((lambda f: f, True), (static, False)):
        model = PedestrianEnvironmentModel(Config(method="paper"))
        model.update(make(a))
        boxes = model.predict_tracks(make(b)).boxes
        assert bool(abs(boxes[0, 0] - a.detections.boxes[0, 0]) > 50.0) is moved


def test_a_walkers_swinging_box_is_predicted_whole():
    """A near walker's box (KITTI 0016 frame 28): its left edge jumps 37 px in one frame while the
    right edge stays (the legs swing). Extrapolated edge by edge, the next prediction is inverted
    (-10 px wide; 8 px wide on the drive, where the neighbour's detection then overlapped it
    better); moved whole (both u edges by their mean velocity) the box keeps its 27 px."""
    from pedenv.tracking.prediction import box_displacement, predict_boxes

    swing = np.array([[37.0, 2.0, 0.0, 4.0]])  # left edge +37 px, right edge still; top +2, bottom +4
    predicted = predict_boxes(np.array([[995.0, 166.0, 1022.0, 310.0]]), swing, 0.0, True)
    np.testing.assert_allclose(predicted, [[1013.5, 168.0, 1040.5, 314.0]])
    np.testing.assert_allclose(box_displacement(swing), [[18.5, 2.0, 18.5, 4.0]])
