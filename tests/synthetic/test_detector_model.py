"""The detector model: noise, misses, false positives, confidences, determinism, options."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.records import Camera, EgoPose, Frame, GroundTruth
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic.detector import DetectorModel
from pedenv.synthetic.walker import body_keypoints

CAMERA = Camera.from_fov(1600, 900, 64.5, height_m=1.5)
TORSO = [KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER, KP.LEFT_HIP, KP.RIGHT_HIP, KP.LEFT_KNEE, KP.RIGHT_KNEE]


def person_frame(index: int, height_px: float, centre_u: float = 800.0, scene: str = "unit", people: int = 1,
                 visible: bool = True) -> Frame:
    """A frame with ``people`` side-by-side front-view persons ``height_px`` tall (ankles to eyes)."""
    body = body_keypoints(np.ones(1), np.zeros(1), np.zeros(1), np.zeros((1, 2)))[0]
    shape = -body[:, [1, 2]] / np.ptp(body[:, 2])  # unit pixel height
    kp = np.stack([shape * height_px + [centre_u + 3 * height_px * i, 450 + height_px / 2] for i in range(people)])
    gt = GroundTruth(np.arange(people), np.zeros((people, 3)), np.zeros((people, 4)) + [0, 0, 1, 1], kp,
                     np.full((people, 17), visible))
    return Frame(index, 0.1 * index, CAMERA, EgoPose.from_xy_yaw(0, 0, 0), ground_truth=gt, scene=scene)


def test_registered_as_pose_backend():
    backend = create_detector("detector-model", seed=3)
    assert isinstance(backend, DetectorModel) and backend.name == "detector-model" and backend.seed == 3


@pytest.mark.parametrize("height_px, expected_std", [(300.0, 1.5), (100.0, 2.25), (30.0, 3.5)])
def test_keypoint_noise_grows_as_persons_shrink(height_px, expected_std):
    model = DetectorModel(seed=1, false_positives_per_frame=0.0, half_detection_height_px=0.0, detection_slope_px=1.0)
    assert model.noise_std_px(np.array([height_px]))[0] == pytest.approx(expected_std, abs=0.05)
    errors = []
    for i in range(300):
        frame = person_frame(i, height_px)
        det = model(frame)
        errors.append(det.keypoints[0, TORSO] - frame.ground_truth.keypoints[0, TORSO])
    assert np.std(errors) == pytest.approx(expected_std, rel=0.1)


@pytest.mark.parametrize("height_px, low, high", [(15.0, 0.25, 0.40), (25.0, 0.45, 0.55), (80.0, 0.97, 1.0),
                                                  (300.0, 0.999, 1.0)])
def test_misses_grow_with_distance(height_px, low, high):
    model = DetectorModel(seed=2, false_positives_per_frame=0.0)
    assert low <= model.detection_probability(np.array([height_px]))[0] <= high
    rate = np.mean([len(model(person_frame(i, height_px, people=10))) / 10 for i in range(200)])
    assert low - 0.03 <= rate <= high + 0.01


def test_false_positive_rate_and_shape():
    model = DetectorModel(seed=3)
    empty = Frame(0, 0.0, CAMERA, EgoPose.from_xy_yaw(0, 0, 0), ground_truth=GroundTruth.empty(), scene="empty")
    dets = [model(Frame(i, 0.1 * i, CAMERA, empty.ego, ground_truth=empty.ground_truth, scene="empty"))
            for i in range(3000)]
    counts = np.array([len(d) for d in dets])
    assert counts.mean() == pytest.approx(0.05, abs=0.015)
    heights = np.concatenate([d.boxes[:, 3] - d.boxes[:, 1] for d in dets])
    assert heights.max() < 70.0 and (np.concatenate([d.confidences for d in dets]) < 0.5).all()


def test_confidences_like_a_pose_network():
    model = DetectorModel(seed=4, false_positives_per_frame=0.0)
    big = np.concatenate([model(person_frame(i, 300.0)).confidences for i in range(50)])
    small = np.concatenate([model(person_frame(i, 40.0)).confidences for i in range(200)])
    unseen = np.concatenate([model(person_frame(i, 300.0, visible=False)).confidences for i in range(50)])
    assert big[:, TORSO].mean() > 0.85 and 0.5 < small[:, TORSO].mean() < big[:, TORSO].mean() - 0.2
    assert unseen.max() <= 0.25 and unseen.min() > 0.0
    assert big[:, [KP.LEFT_WRIST, KP.RIGHT_ANKLE]].mean() < big[:, TORSO].mean()


def test_unseen_keypoints_are_guessed_inside_the_image():
    frame = person_frame(0, 200.0, centre_u=-10.0)  # left half of the person is outside
    det = DetectorModel(seed=0)(frame)
    assert (det.keypoints[..., 0] >= 0).all() and (det.keypoints[..., 0] <= 1599).all()


def test_person_offset_stays_with_the_person_and_scales_with_height():
    model = DetectorModel(seed=4, false_positives_per_frame=0.0, half_detection_height_px=0.0, detection_slope_px=1.0,
                          noise_px_small=0.0, noise_px_large=0.0, person_offset_u=0.03, person_offset_v=0.02)

    def offset(index, scene, height_px=200.0):  # (2,) px: the one person's mean keypoint shift
        frame = person_frame(index, height_px, scene=scene)
        return (model(frame).keypoints[0] - frame.ground_truth.keypoints[0]).mean(axis=0)

    persons = np.array([offset(0, f"street-{k}") for k in range(400)])  # person 0 of 400 scenes
    assert np.std(persons[:, 0]) / 200.0 == pytest.approx(0.03, rel=0.15)
    assert np.std(persons[:, 1]) / 200.0 == pytest.approx(0.02, rel=0.15)
    for k in range(3):  # the same person keeps their offset from frame to frame, scaled by their height
        assert np.allclose([offset(i, f"street-{k}") for i in range(10)], persons[k], atol=1e-9)
        assert np.allclose(offset(7, f"street-{k}", height_px=100.0), persons[k] / 2, atol=1e-9)
    plain = DetectorModel(seed=4)(person_frame(0, 200.0)).keypoints
    assert np.array_equal(plain, DetectorModel(seed=4, person_offset_u=0.0)(person_frame(0, 200.0)).keypoints)


def test_deterministic_per_seed_scene_and_frame():
    frame = person_frame(5, 60.0, people=8)
    a, b = DetectorModel(seed=1)(frame), DetectorModel(seed=1)(frame)
    assert np.array_equal(a.keypoints, b.keypoints) and np.array_equal(a.confidences, b.confidences)
    others = [DetectorModel(seed=2)(frame), DetectorModel(seed=1)(person_frame(6, 60.0, people=8)),
              DetectorModel(seed=1)(person_frame(5, 60.0, people=8, scene="other"))]
    for other in others:
        assert a.keypoints.shape != other.keypoints.shape or not np.array_equal(a.keypoints, other.keypoints)


@pytest.mark.parametrize("kwargs", [{"seed": "x"}, {"noise_px_large": -1.0}, {"noise_px_small": 100.0},
                                    {"detection_slope_px": 0.0}, {"false_positives_per_frame": 50.0},
                                    {"extremity_noise_factor": 0.5}, {"half_detection_height_px": True},
                                    {"person_offset_u": -0.1}, {"person_offset_v": 0.9}])
def test_options_are_range_checked(kwargs):
    with pytest.raises(ValueError):
        DetectorModel(**kwargs)


def test_frame_without_ground_truth_skeletons_is_an_input_error():
    frame = Frame(3, 0.3, CAMERA, EgoPose.from_xy_yaw(0, 0, 0), scene="bare")
    with pytest.raises(InputError, match="frame 3 of bare"):
        DetectorModel()(frame)


@pytest.mark.parametrize("outside", [0.0, 1.0])
def test_false_positives_outside_people_keep_their_rate(outside):
    """With ``false_positives_outside_people`` no ghost lies half inside a person, and as many appear."""
    from pedenv.boxes import containment_matrix
    from pedenv.records import boxes_from_keypoints

    model = DetectorModel(seed=5, false_positives_per_frame=5.0, false_positives_outside_people=outside)
    inside, ghosts = 0, 0
    for i in range(200):
        frame = person_frame(i, 200.0, centre_u=200.0, people=3)
        people = boxes_from_keypoints(frame.ground_truth.keypoints, np.ones((3, 17), bool))
        det = model(frame)
        ghost = det.boxes[det.boxes[:, 3] - det.boxes[:, 1] < 70.0]
        ghosts += len(ghost)
        inside += int((containment_matrix(ghost, people).max(1) >= 0.5).sum())
    assert ghosts / 200 == pytest.approx(5.0, abs=0.3)
    assert inside == 0 if outside else inside > 20
