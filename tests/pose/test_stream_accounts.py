"""What the stream remembers of tracks: when each was seen, where, and the box its crop must hold."""

import numpy as np

from pedenv.pose.stream_accounts import TrackFinder


def test_a_track_crop_holds_both_the_prediction_and_where_the_track_was_last_detected():
    finder = TrackFinder()
    ids = np.array([7, 9])
    predicted = np.array([[100.0, 200, 130, 280], [400, 200, 430, 280]])
    finder.update(ids, predicted, np.array([[102.0, 202, 131, 281]]), 1.0, 0.3)  # track 7 detected, 9 missed
    np.testing.assert_allclose(finder.unseen_s(ids, 1.2), [0.2, 0.0])  # 9 is new to the finder: counted from now
    moved = np.array([[112.0, 200, 142, 280], [410, 200, 440, 280]])  # the next frame's prediction: 10 px right
    np.testing.assert_allclose(finder.search_boxes(ids, moved), [[102, 200, 142, 281], [410, 200, 440, 280]])
    np.testing.assert_allclose(finder.search_boxes(np.zeros(0, np.int64), np.zeros((0, 4))), np.zeros((0, 4)))
