"""Bad input: one clear error naming frame and field, or handled as data."""

from dataclasses import replace

import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame

from standing_people import frame_with_people


@pytest.mark.parametrize(
    "build, message",
    [
        (
            lambda: Detections(np.zeros((3, 20, 2)), np.zeros((3, 20))),
            r"keypoints must have shape \(N, 17, 2\), got \(3, 20, 2\)",
        ),
        (lambda: Detections(np.zeros((2, 17, 2)), np.zeros((3, 17))), r"confidences must have shape \(2, 17\)"),
        (lambda: Camera(np.zeros((3, 3)), 1600, 900), "intrinsics must be an invertible camera matrix"),
        (lambda: Camera(np.eye(3), 0, 900), "image size must be positive"),
        (lambda: EgoPose(np.zeros(3), np.diag([1.0, 1.0, -1.0])), "ego rotation must be orthonormal and right-handed"),
        (lambda: Frame(7, 0.0, Camera.from_fov(), None), "frame 7: ego must be a EgoPose, got NoneType"),
        (
            lambda: Frame(7, float("nan"), Camera.from_fov(), EgoPose.from_xy_yaw(0, 0, 0)),
            "frame 7: timestamp must be finite",
        ),
    ],
)
def test_bad_records_name_the_field(build, message):
    with pytest.raises(InputError, match=message):
        build()


def test_timestamps_going_backwards_name_the_frame():
    model = PedestrianEnvironmentModel()
    model.update(frame_with_people(0, 1.0, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))
    with pytest.raises(InputError, match=r"frame 1: field 'timestamp' goes backwards"):
        model.update(frame_with_people(1, 0.9, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))


def test_a_huge_timestamp_is_shown_short():
    model = PedestrianEnvironmentModel()
    model.update(frame_with_people(0, 1e300, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))
    with pytest.raises(InputError) as err:
        model.update(frame_with_people(1, 1.0, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))
    assert str(err.value) == "frame 1: field 'timestamp' goes backwards or repeats (1.000000 s after 1e+300 s)"


def test_missing_detections_name_the_frame():
    with pytest.raises(InputError, match="frame 3 of scene 'x': field 'detections' is missing"):
        PedestrianEnvironmentModel().update(Frame(3, 0.0, Camera.from_fov(), EgoPose.from_xy_yaw(0, 0, 0), scene="x"))


def test_empty_frames_and_nan_keypoints_are_data():
    model = PedestrianEnvironmentModel()
    ego = EgoPose.from_xy_yaw(0, 0, 0)
    empty = replace(frame_with_people(0, 0.0, ego, []), detections=Detections.empty())
    assert len(model.update(empty).pedestrians) == 0
    frame = frame_with_people(1, 0.1, ego, [(25.0, 2.0)])
    kp = frame.detections.keypoints.copy()
    kp[0, :4] = np.nan
    state = model.update(replace(frame, detections=Detections(kp, np.ones((1, 17)))))
    p = state.pedestrians
    assert p.confidences[0, :4].tolist() == [0, 0, 0, 0]
    assert np.isfinite(p.positions).all() and len(p) == 1


def test_update_refuses_what_is_not_a_frame():
    with pytest.raises(InputError, match="update\\(\\) takes a pedenv.records.Frame, got dict"):
        PedestrianEnvironmentModel().update({"timestamp": 0.0})
