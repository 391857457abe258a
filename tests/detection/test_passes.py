"""The far pyramid on a real frame: the rows of the finer level fitted to the people the coarser ones found."""

import pytest

from pedenv.detection import passes
from pedenv.detection.config import FIT_MIN_SCORE
from pedenv.evaluation.detections import match_detections, mot17_samples
from pedenv.images import read_image_rgb

from shared_paths import REAL_SAMPLES

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model]


def test_a_dark_frame_fits_the_x2_rows_to_less_sure_people_and_finds_more(pose_cache, monkeypatch):
    """MOT17-10 (a street at night, no calibration): the whole-frame and x1 passes find only
    two people scoring >= 0.5, too few to fit the rows of the x2 level, which then covers the
    whole image (at x1.7, ``whole_image_finest_mpx``; before it was skipped and x2 found 4 more
    of the 9 people >= 80 px then counted); counting those scoring >= fit_min_score (0.35) fits
    the rows: the same people found (measured: 13 of 13 >= 80 px both ways) for half the cost
    (measured: 17.0 vs 35.4 units)."""
    from pedenv.detection import create_detector
    from pedenv.pose.models import find_onnx_model

    sample = next(s for s in mot17_samples(REAL_SAMPLES / "mot17") if s.name == "MOT17-10-FRCNN/000002")
    image = read_image_rgb(sample.image_path)
    tall = sample.required & (sample.heights >= 80)
    found, notes, units = {}, {}, {}
    for fit_min_score in (0.5, FIT_MIN_SCORE):  # the constant's value, against surer people only
        monkeypatch.setattr(passes, "FIT_MIN_SCORE", fit_min_score)
        pose = create_detector("onnx", model_path=find_onnx_model(None, cache=pose_cache), detection="far")
        dets = pose.detect(image)  # no calibration: the finer levels' rows come from the fit
        found[fit_min_score] = int(match_detections(sample, dets.boxes, dets.scores).hit[tall].sum())
        notes[fit_min_score] = pose.last_note
        units[fit_min_score] = sum(p.input_size[0] * p.input_size[1] for p in pose.last_passes) / (384 * 640)
    assert FIT_MIN_SCORE == 0.35
    assert "whole image at the finest level: no calibration, too few people to fit" in notes[0.5]
    assert "x2.00 rows" in notes[0.35] and "(fit to" in notes[0.35]
    assert found[0.35] >= found[0.5] >= 12
    assert units[0.35] <= 0.6 * units[0.5]
