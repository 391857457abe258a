"""Re-detection of missed tracks in crops: which tracks, which crop, the real network on a real frame."""

from dataclasses import replace

import numpy as np
import pytest

from pedenv.boxes import iou_matrix
from pedenv.config import Config
from pedenv.detection import RedetectConfig
from pedenv.detection.redetect import Redetection, crop_pass, missed_tracks
from pedenv.detection.track_search import nearest_person, nearest_track
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Detections, EgoPose, Frame

ON = RedetectConfig(enabled=True)


@pytest.mark.parametrize("predicted, hits, detections, expected", [
    # a track whose predicted box a detection overlaps is not missed; the other one is
    ([[100, 100, 140, 200], [300, 100, 340, 200]], [5, 5], [[102, 102, 142, 202]], [1]),
    # a one-hit track is not searched (min_hits 2)
    ([[100, 100, 140, 200], [300, 100, 340, 200]], [1, 3], [], [1]),
    # most-seen first
    ([[100, 100, 140, 200], [300, 100, 340, 200]], [2, 9], [], [1, 0]),
    # mostly outside the 640x480 image, or tiny there: not searched
    ([[600, 100, 700, 200], [10, 470, 30, 500], [10, 10, 30, 60]], [4, 4, 4], [], [2]),
    # no tracks
    (np.zeros((0, 4)), [], [[0, 0, 10, 10]], []),
])
def test_missed_tracks(predicted, hits, detections, expected):
    rows = missed_tracks(np.array(predicted, float), np.array(hits), np.array(detections, float).reshape(-1, 4),
                         (480, 640), ON)
    assert rows.tolist() == expected


def test_missed_tracks_stops_at_max_crops():
    predicted = np.array([[10.0 + 60 * i, 100, 50 + 60 * i, 200] for i in range(6)])
    rows = missed_tracks(predicted, np.arange(6) + 2, np.zeros((0, 4)), (480, 640), replace(ON, max_crops=2))
    assert rows.tolist() == [5, 4]
    assert missed_tracks(predicted, np.arange(6) + 2, np.zeros((0, 4)), (480, 640), replace(ON, max_crops=0)).size == 0


@pytest.mark.parametrize("boxes, whole, expected", [
    # the nearest of two; one 0.3 heights off, one 0.1
    ([[130, 100, 170, 200], [110, 100, 150, 200]], [True, True], [1]),
    # a cut one does not count
    ([[130, 100, 170, 200], [110, 100, 150, 200]], [True, False], [0]),
    # too far (0.8 heights) or of another size (2x): none
    ([[180, 100, 220, 200], [100, 0, 160, 200]], [True, True], []),
    ([], [], []),
])
def test_nearest_person(boxes, whole, expected):
    found = nearest_person(np.array([100.0, 100, 140, 200]), np.array(boxes, float).reshape(-1, 4),
                           np.array(whole, bool), ON)
    assert found.tolist() == expected


def test_nearest_track_measures_in_each_tracks_heights():
    predicted = np.array([[100.0, 100, 140, 200], [160, 150, 170, 175]])  # a 100 px and a 25 px tall track
    # 40 px from the first's centre (0.4 heights), 33 px from the second's (1.3 heights)
    assert nearest_track(np.array([140.0, 100, 180, 200]), predicted) == 0
    assert nearest_track(np.array([158.0, 150, 170, 176]), predicted) == 1


def test_crop_pass_holds_the_box_with_context_inside_the_image():
    # a 60 px person: margin 0.5 -> 60 + 60 px tall, min 128 px; scale 2 -> input 256
    step = crop_pass(np.array([500.0, 200, 524, 260]), (370, 1224))
    x0, y0, x1, y1 = step.region
    assert (x1 - x0, y1 - y0) == (128, 128)
    assert x0 <= 500 and x1 >= 524 and y0 <= 200 and y1 >= 260
    assert step.input_size == (256, 256)
    # near the image corner: moved inside, never past the edges
    x0, y0, x1, y1 = crop_pass(np.array([-10.0, 300, 20, 380]), (370, 1224)).region
    assert x0 == 0 and y1 == 370 and y1 - y0 == 160
    # a tall person: the input is capped at max_input_px, a multiple of 32
    step = crop_pass(np.array([100.0, 0, 300, 600]), (1080, 1920))
    assert max(step.input_size) == 640 and all(s % 32 == 0 for s in step.input_size)
    assert step.region[3] - step.region[1] == 960  # 600 + 2 * 300, clamped to max_crop_px


@pytest.mark.parametrize("field, value, message", [
    ("match_distance", -0.1, r"redetect.match_distance must be in \[0.0, 2.0\]"),
    ("max_crops", 65, r"redetect.max_crops must be an integer in \[0, 64\]"),
    ("match_distance", 3.0, "redetect.match_distance"),
    ("enabled", "yes", "redetect.enabled must be true or false"),
])
def test_bad_settings_are_refused(field, value, message):
    with pytest.raises(ValueError, match=message):
        RedetectConfig(**{field: value})


def test_the_fused_preset_turns_it_on():
    assert not Config(method="paper").redetect.enabled
    assert Config().redetect.enabled  # fused, the default method
    assert configure(Config(method="paper"), "fused").redetect.enabled
    assert not configure(Config(), "paper").redetect.enabled
    assert Config.from_dict({"redetect": {"max_crops": 2}}).redetect.max_crops == 2


def _person(box) -> Detections:
    u0, v0, u1, v1 = box
    kp = np.column_stack([np.linspace(u0, u1, 17), np.linspace(v0, v1, 17)])
    return Detections(kp[None], np.full((1, 17), 0.9), np.array([box], float), np.array([0.9]))


def test_predicted_tracks_move_with_the_tracks_image_velocity(camera):
    model = PedestrianEnvironmentModel(configure(Config(), "fused"))  # predict_motion on
    ego = EgoPose.from_xy_yaw(0.0, 0.0, 0.0)
    frame = Frame(0, 0.0, camera, ego, _person([800, 400, 840, 500]))
    assert model.predict_tracks(frame).boxes.shape == (0, 4)
    model.update(frame)
    model.update(Frame(1, 0.1, camera, ego, _person([810, 400, 850, 500])))
    tracks = model.predict_tracks(Frame(2, 0.2, camera, ego))
    assert tracks.ids.tolist() == [1] and tracks.hits.tolist() == [2]
    # smoothed velocity 0.5 * 10 px per frame: the tracker's own prediction
    np.testing.assert_allclose(tracks.boxes[0], [815, 400, 855, 500])
    np.testing.assert_allclose(model.tracks.tracks.boxes[0], [810, 400, 850, 500])  # the model is unchanged


@pytest.mark.onnx_model
def test_a_person_the_main_pass_missed_is_found_again_in_a_crop():
    from pedenv.datasets.kitti import KittiTrackingDataset
    from pedenv.detection import create_detector
    from pedenv.pose.postprocess import frame_image

    from shared_paths import REAL_SAMPLES

    config = configure(Config(), "fused")
    backend = create_detector("onnx", score_threshold=config.tracking.pose_score_threshold)
    assert backend.redetection is None  # no re-detection unless the run's settings turn it on
    on = create_detector("onnx", score_threshold=config.tracking.pose_score_threshold, redetect=config.redetect)
    assert on.redetection is not None and on.redetection.config == config.redetect
    assert create_detector("onnx", detection="stream", redetect=config.redetect).redetection is None  # its own search
    frame = next(KittiTrackingDataset(REAL_SAMPLES / "kitti" / "tracking_mini").frames("0016"))
    main = backend(frame)
    model = PedestrianEnvironmentModel(config)
    redetect = Redetection(config.redetect)
    for k in range(2):  # two frames with everyone seen: tracks with 2 hits
        before = model.update(replace(frame, index=k, timestamp=0.1 * k, detections=main))
    # the third frame's main pass "misses" the tallest person who started a track (score >= 0.25)
    tallest = int(np.argmax(np.where(main.scores >= 0.25, main.boxes[:, 3] - main.boxes[:, 1], 0.0)))
    missing = main.take(np.delete(np.arange(len(main)), tallest))
    third = replace(frame, index=2, timestamp=0.2)
    tracks, image = model.predict_tracks(third), frame_image(third)
    size = (image.shape[0], image.shape[1])
    found = redetect(backend.network, image, size, missing, tracks, backend.decoding)
    assert redetect.crops == 1 and redetect.redetected == 1
    assert len(found) == len(main)
    assert iou_matrix(main.boxes[[tallest]], found.boxes).max() > 0.8
    iou = iou_matrix(found.boxes, found.boxes)
    assert (np.triu(iou, 1) <= 0.5).all()  # nobody twice
    # with everyone detected, no crop runs and nothing changes
    assert len(redetect(backend.network, image, size, main, tracks, backend.decoding)) == len(main)
    assert redetect.crops == 1
    # every track continues, the re-found person's included, and no new one starts
    state = model.update(replace(third, detections=found))
    assert len(before.pedestrians) >= 6
    assert sorted(state.pedestrians.track_ids.tolist()) == sorted(before.pedestrians.track_ids.tolist())
