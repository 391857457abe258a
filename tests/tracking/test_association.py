import numpy as np
import pytest

from pedenv.tracking.association import associate


def test_associate_hungarian_prefers_best_total():
    tracks = np.array([[0, 0, 10, 10], [12, 0, 22, 10]], float)
    dets = np.array([[13, 0, 23, 10], [1, 0, 11, 10], [200, 0, 210, 10]], float)
    matches, lost, fresh = associate(dets, tracks, threshold=-0.3)
    assert sorted(map(tuple, matches.tolist())) == [(0, 1), (1, 0)]
    assert lost.tolist() == [] and fresh.tolist() == [2]


@pytest.mark.parametrize("n_det, n_trk", [(0, 0), (0, 3), (2, 0)])
def test_associate_empty(n_det, n_trk):
    matches, lost, fresh = associate(np.zeros((n_det, 4)), np.zeros((n_trk, 4)))
    assert matches.shape == (0, 2)
    assert lost.tolist() == list(range(n_trk)) and fresh.tolist() == list(range(n_det))


def test_associate_threshold_splits_far_pairs():
    tracks = np.array([[0, 0, 1, 1]], float)
    dets = np.array([[2, 0, 3, 1]], float)  # GIoU -1/3
    assert len(associate(dets, tracks, threshold=-0.3)[0]) == 0
    assert len(associate(dets, tracks, threshold=-0.4)[0]) == 1


def test_height_ratio_rule_keeps_a_small_far_box_off_a_stale_near_one():
    near_track = np.array([[100, 100, 160, 300]], float)      # 200 px tall
    far_detection = np.array([[120, 180, 130, 210]], float)    # 30 px tall, inside the track's box
    assert len(associate(far_detection, near_track, -0.3)[0]) == 1          # the paper's rule joins them
    assert len(associate(far_detection, near_track, -0.3, max_height_ratio=1.5)[0]) == 0
