"""What ``stream`` remembers of tracks: where to search each one, and which person found is it."""

import numpy as np
import pytest

from pedenv.detection import RedetectConfig
from pedenv.detection.track_search import TrackFinder
from pedenv.records import Detections


def person(box) -> Detections:
    box = np.asarray(box, float).reshape(1, 4)
    centre = 0.5 * (box[:, None, :2] + box[:, None, 2:])
    return Detections(np.repeat(centre, 17, axis=1), np.full((1, 17), 0.9), box, np.array([0.9]))


def test_a_track_is_searched_at_its_detected_size_moved_by_the_prediction():
    finder = TrackFinder(RedetectConfig())
    ids = np.array([7, 8])
    detected = np.array([[100.0, 200, 130, 290], [400, 200, 430, 290]])  # 90 px tall
    finder.update(ids, detected, detected, 0.0, 0.3)
    # the tracker's edge velocities shrank track 7's box to 60 px and moved it 10 px right; track 8's
    # box is 300 px away (another person: ids reused, or a wrong association): searched as predicted
    predicted = np.array([[110.0, 215, 140, 275], [700, 200, 730, 290]])
    searched, last = finder.search_boxes(ids, predicted, 1.0)
    np.testing.assert_allclose(last, [detected[0], predicted[1]])
    np.testing.assert_allclose(searched, [[110, 200, 140, 290], predicted[1]])
    searched, last = finder.search_boxes(ids, predicted, 0.0)  # 0: always the predicted box
    np.testing.assert_allclose(searched, predicted)
    np.testing.assert_allclose(last, predicted)
    # ids reused for other people (evaluate-detections' stand-in tracks: last frame's persons in
    # another order): each remembered box is the other id's predicted box, so each is searched as predicted
    swapped = detected[::-1].copy()
    searched, last = finder.search_boxes(ids, swapped, 100.0)
    np.testing.assert_allclose(searched, swapped)
    np.testing.assert_allclose(last, swapped)


def test_a_track_never_detected_here_is_searched_at_its_prediction():
    finder = TrackFinder(RedetectConfig())
    predicted = np.array([[10.0, 20, 30, 80]])
    searched, last = finder.search_boxes(np.array([3]), predicted, 1.0)
    np.testing.assert_allclose(searched, predicted)
    np.testing.assert_allclose(last, predicted)


def test_a_person_found_at_the_last_detection_re_detects_the_track_when_the_motion_was_wrong():
    finder = TrackFinder(RedetectConfig())
    searched = np.array([[160.0, 200, 190, 290], [600, 200, 630, 290]])  # track 0 predicted 60 px right
    last = np.array([[100.0, 200, 130, 290], [600, 200, 630, 290]])
    found = person([101, 202, 131, 291])  # it stood still
    picked = finder.pick(searched, last, [0], [(found, np.zeros(1, bool))])
    assert len(picked) == 1 and picked.boxes[0] == pytest.approx([101, 202, 131, 291])
    assert not len(finder.pick(searched, last, [0], [(found, np.ones(1, bool))]))  # cut by the crop: not it


def test_forgotten_tracks_are_dropped():
    finder = TrackFinder(RedetectConfig())
    box = np.array([[0.0, 0, 10, 30]])
    finder.update(np.array([1]), box, box, 0.0, 0.3)
    finder.update(np.array([2]), box, box, 0.1, 0.3)  # track 1 is no longer live
    _, last = finder.search_boxes(np.array([1]), box + 50, 10.0)
    np.testing.assert_allclose(last, box + 50)  # nothing remembered of it
