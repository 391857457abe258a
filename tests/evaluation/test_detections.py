"""Detection matching and the datasets' ignore rules, on the real samples' ground truth."""

import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.evaluation.detections import (
    DetectionSample,
    load_samples,
    match_detections,
    summarize,
)

from shared_paths import REAL_SAMPLES


@pytest.fixture(scope="module")
def samples():
    return load_samples(REAL_SAMPLES)


def test_samples_cover_the_three_datasets(samples):
    by = {d: [s for s in samples if s.dataset == d] for d in ("kitti", "mot17", "nuscenes")}
    assert [len(v) for v in by.values()] == [9, 39, 5]
    assert sum(int(s.required.sum()) for s in by["kitti"]) == 25  # 24 tracking + 1 object
    assert sum(int(s.required.sum()) for s in by["mot17"]) == 534  # visibility >= 0.5
    assert sum(len(s.boxes) for s in by["nuscenes"]) == 19
    assert all(s.geometry is not None for s in by["kitti"] + by["nuscenes"])
    assert all(s.geometry is None for s in by["mot17"])
    assert not any(s.count_false_positives for s in by["nuscenes"])


def test_ground_truth_as_detections_is_perfect(samples):
    matches = [match_detections(s, s.boxes, np.linspace(1, 0.5, len(s.boxes))) for s in samples]
    summary = summarize(samples, matches, [1.0] * len(samples))
    assert summary["all"]["recall"] == 1.0 and summary["all"]["precision"] == 1.0
    assert summary["all"]["persons"] == 578
    assert [b["persons"] for b in summary["kitti"]["by_distance"]] == [10, 15, 0, 0]
    assert sum(b["persons"] for b in summary["mot17"]["by_height"]) == 534


def test_detections_in_ignore_regions_are_not_false_positives(samples):
    kitti_16 = next(s for s in samples if s.name == "tracking 0016/000012")
    dontcare = kitti_16.ignore[:1]
    inside = np.r_[dontcare[0, :2] + 2, dontcare[0, 2:] - 2][None]
    assert match_detections(kitti_16, inside, np.ones(1)).false_positives == 0
    nowhere = np.array([[5.0, 5.0, 25.0, 60.0]])  # the sky corner
    assert match_detections(kitti_16, nowhere, np.ones(1)).false_positives == 1
    mot = next(s for s in samples if s.dataset == "mot17" and len(s.ignore))
    assert match_detections(mot, mot.ignore[:1], np.ones(1)).false_positives == 0


def test_optional_boxes_are_neither_hits_nor_false_positives():
    sample = DetectionSample("mot17", "x", REAL_SAMPLES, np.array([[0, 0, 10, 40], [50, 0, 60, 40.0]]),
                             np.array([40.0, 40.0]), np.full(2, np.nan), np.array([True, False]))
    m = match_detections(sample, np.array([[50, 0, 60, 40.0], [100, 0, 110, 40.0]]), np.array([0.9, 0.8]))
    assert m.hit.tolist() == [False, False] and m.false_positives == 1


def test_the_visible_part_of_an_occluded_person_is_counted_apart_once():
    # an optional (mostly occluded) person 200 px tall; the detector sees their upper 80 px
    sample = DetectionSample("mot17", "x", REAL_SAMPLES, np.array([[0, 0, 50, 200], [200, 0, 250, 200.0]]),
                             np.array([200.0, 200.0]), np.full(2, np.nan), np.array([False, True]))
    upper = np.array([[2, 0, 48, 80], [5, 10, 45, 90], [100, 0, 140, 80.0]])  # twice in it, once beside
    m = match_detections(sample, upper, np.array([0.9, 0.8, 0.7]))
    assert (m.occluded_parts, m.false_positives) == (1, 2)
    summary = summarize([sample], [m], [1.0])["all"]
    assert summary["occluded_parts"] == 1 and summary["precision"] == summary["precision_strict"] == 0.0
    hit = match_detections(sample, np.vstack([upper, [[200, 0, 250, 200.0]]]), np.array([0.9, 0.8, 0.7, 0.95]))
    summary = summarize([sample], [hit], [1.0])["all"]
    assert summary["precision"] == pytest.approx(1 / 3) and summary["precision_strict"] == pytest.approx(1 / 4)


def test_one_detection_matches_one_person_only():
    sample = DetectionSample("kitti", "x", REAL_SAMPLES, np.array([[0, 0, 10, 40], [1, 0, 11, 40.0]]),
                             np.array([40.0, 40.0]), np.array([10.0, 20.0]), np.ones(2, bool))
    m = match_detections(sample, np.array([[0, 0, 10, 40.0]]), np.ones(1))
    assert int(m.hit.sum()) == 1 and m.false_positives == 0


def test_missing_data_root(tmp_path):
    with pytest.raises(InputError, match="data root not found"):
        load_samples(tmp_path / "nowhere")
    with pytest.raises(InputError, match="no kitti/, mot17/ or nuscenes-0061/ samples"):
        load_samples(tmp_path)
