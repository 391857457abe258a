"""The cascade for small people: which candidates, which verification, and the settings' checks."""

import math

import numpy as np
import pytest

from pedenv.detection.cascade import accept, candidates
from pedenv.detection.config import CascadeConfig, DetectionConfig, StreamConfig
from pedenv.errors import InputError
from pedenv.records import Detections

#: Measured on MOT17-13 frame 1: far finds 2 of its 8 people 40-80 px tall (1 false positive),
#: far + cascade 3 (3 false positives), the cascade confirming 3 in 2 packed inputs.
CASCADE_GAIN = 1
CASCADE_EXTRA_FALSE = 3


def people(boxes, scores, conf=0.8) -> Detections:
    boxes = np.array(boxes, float).reshape(-1, 4)
    kps = np.repeat(0.5 * (boxes[:, None, :2] + boxes[:, None, 2:]), 17, axis=1)
    return Detections(kps, np.full((len(boxes), 17), conf), boxes, np.array(scores, float))


def test_candidates_are_small_new_people_best_first():
    low = people([[100, 100, 120, 150],  # 50 px: a candidate
                  [300, 100, 320, 110],  # 10 px: too small
                  [500, 100, 600, 400],  # 300 px: too tall for the cascade
                  [702, 101, 722, 151],  # the person already kept at 700: a duplicate
                  [900, 100, 915, 140],  # 40 px, better score: first
                  [101, 101, 121, 151]],  # the first one again: merged
                 [0.1, 0.2, 0.2, 0.2, 0.15, 0.08])
    kept = people([[700, 100, 720, 150]], [0.9])
    found = candidates(low, kept)
    np.testing.assert_allclose(found.boxes, [[900, 100, 915, 140], [100, 100, 120, 150]])


@pytest.mark.parametrize("box, score, conf, cut, expected", [
    ([100, 100, 120, 150], 0.5, 0.8, False, [0]),  # whole, sure, plausible, same place
    ([100, 100, 120, 150], 0.5, 0.8, True, []),  # cut by the crop's edge
    ([100, 100, 120, 150], 0.1, 0.8, False, []),  # the zoomed pass is not sure either
    ([100, 100, 120, 150], 0.5, 0.2, False, []),  # no plausible skeleton (a pole, a sign)
    ([112, 100, 132, 150], 0.5, 0.8, False, []),  # somewhere else (IoU 0.25)
])
def test_accept_needs_a_whole_plausible_skeleton_at_the_same_place(box, score, conf, cut, expected):
    found = people([box], [score], conf)
    rows = accept(np.array([100.0, 100, 120, 150]), found, np.array([cut]))
    assert rows.tolist() == expected


@pytest.mark.parametrize("section, changes, field", [
    ("stream", {"budget_units": 0.0}, "detection.stream.budget_units"),
    ("stream", {"budget_units": 0.5}, "detection.stream.budget_units"),  # below one pass
    ("stream", {"scan_period_s": 0.0}, "detection.stream.scan_period_s"),
    ("stream", {"scan_period_s": math.nan}, "detection.stream.scan_period_s"),
    ("stream", {"packed_width": 600}, "detection.stream.packed_width"),
    ("stream", {"cold_start": "yes"}, "detection.stream.cold_start"),
    ("stream", {"credit_units": -1.0}, "detection.stream.credit_units"),
    ("stream", {"credit_units": math.nan}, "detection.stream.credit_units"),
    ("stream", {"max_gap_s": 0.0}, "detection.stream.max_gap_s"),
    ("stream", {"packed_height": 96}, "detection.stream.packed_height"),
    ("cascade", {"enabled": "yes"}, "detection.cascade.enabled"),
    ("cascade", {"max_units": 0}, "detection.cascade.max_units"),
    ("cascade", {"max_units": 17}, "detection.cascade.max_units"),
])
def test_bad_values_get_one_clear_error_naming_the_field(section, changes, field):
    make = StreamConfig if section == "stream" else CascadeConfig
    with pytest.raises(InputError, match=field.replace(".", r"\.")):
        make(**changes)


def test_the_stream_mode_is_named_and_saved_with_its_sections():
    config = DetectionConfig.named("stream")
    saved = config.to_dict()
    assert saved["mode"] == "stream" and saved["stream"]["budget_units"] == 3.0
    assert saved["cascade"]["enabled"] is True


@pytest.mark.ultralytics
@pytest.mark.onnx_model
def test_the_cascade_finds_more_small_people_on_a_real_frame(pose_cache):
    """MOT17-13 frame 1 (a real street, many people 40-80 px tall): far with and without the cascade."""
    from dataclasses import replace
    from pathlib import Path

    from pedenv.detection import create_detector
    from pedenv.evaluation.detections import match_detections, mot17_samples
    from pedenv.images import read_image_rgb
    from pedenv.pose.models import find_onnx_model

    root = Path(__file__).resolve().parents[2].parent / "shared" / "samples" / "real" / "mot17"
    sample = next(s for s in mot17_samples(root) if s.name == "MOT17-13-FRCNN/000001")
    image = read_image_rgb(sample.image_path)
    small = sample.required & (sample.heights >= 40) & (sample.heights < 80)
    found = {}
    for cascade in (False, True):
        config = DetectionConfig.named("far")
        config = replace(config, cascade=replace(config.cascade, enabled=cascade))
        pose = create_detector("onnx", model_path=find_onnx_model(None, cache=pose_cache), detection=config)
        dets = pose.detect(image, sample.geometry)
        match = match_detections(sample, dets.boxes, dets.scores)
        found[cascade] = (int((match.hit & small).sum()), match.false_positives)
        assert ("cascade" in pose.last_note) == cascade
    assert found[True][0] >= found[False][0] + CASCADE_GAIN
    assert found[True][1] <= found[False][1] + CASCADE_EXTRA_FALSE
