"""Fitted detector-model profiles reproduce the real network's measurements they came from."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pedenv.detection import create_detector
from pedenv.synthetic.detector import PROFILES, DetectorModel
from pedenv.synthetic.detector_fit import (
    BINS,
    fit_detection_curve,
    logistic,
    recall_by_bin,
    synthetic_offsets,
    synthetic_recall,
)

RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results"
FITTED = {name: RESULTS / f"detector_{name}.json" for name in ("yolo11n-pose-single", "yolo11n-pose-fast",
                                                                 "yolo11n-pose-far", "yolo11n-pose-native")}


def measured(profile: str) -> dict:
    return json.loads(FITTED[profile].read_text())


@pytest.mark.parametrize("profile", sorted(FITTED))
def test_profile_holds_the_fitted_values(profile):
    fit, params = measured(profile)["fit"], PROFILES[profile]
    for name in ("half_detection_height_px", "detection_slope_px", "noise_px_small", "noise_px_large",
                 "false_positives_per_frame"):
        assert params[name] == pytest.approx(fit[name], rel=0.02, abs=0.01), name
    for name in ("person_offset_u", "person_offset_v"):  # measured for far only; 0 where not measured
        assert params[name] == pytest.approx(fit.get(name, 0.0), abs=1e-4), name


def test_far_profile_gives_each_person_the_real_networks_persistent_offset(default_scenes):
    """The spread across persons of the skeleton's offset from the true ground point, in box
    heights: the fitted model on the synthetic scenes reproduces what the fit recorded, and
    that lies within 25 % of the real network's against the 3D truth (KITTI, nuScenes)."""
    offsets = measured("yolo11n-pose-far")["person_offset"]
    acc, _ = synthetic_offsets(DetectorModel(seed=0, profile="yolo11n-pose-far"), default_scenes)
    synthetic = acc.summary()
    for key in ("foot_across_persons", "column_across_persons"):
        assert synthetic[key] == pytest.approx(offsets["synthetic_with"][key], abs=1e-4), key
        assert synthetic[key] == pytest.approx(offsets["real_3d_truth"][key], rel=0.25), key
        assert offsets["synthetic_without"][key] < 0.6 * offsets["real_3d_truth"][key], key  # what the fit added


@pytest.mark.parametrize("profile", sorted(FITTED))
def test_synthetic_recall_matches_the_real_network_in_every_bin(profile, default_scenes):
    table = measured(profile)
    real = [row["mean"] for row in table["recall_by_box_height"]["all"]]
    model = DetectorModel(seed=0, profile=profile)
    frames = [f for scene in default_scenes for f in scene.frames[::3]]
    heights, detected = synthetic_recall(frames, model, table["span_over_box_height"]["median"])
    synthetic = recall_by_bin(heights, detected)
    counts = np.bincount(np.searchsorted([b[1] for b in BINS[:-1]], heights, side="right"), minlength=len(BINS))
    assert counts.min() >= 50  # every bin has persons to compare
    for (low, _), r, s in zip(BINS, real, synthetic):
        assert abs(r - s) <= 0.10, f"bin from {low} px: real {r:.2f}, synthetic {s:.2f}"
    fit = table["fit"]
    if "synthetic_recall_by_bin" in fit:  # fitted to the recall table: the model gives what the fit recorded
        assert synthetic == pytest.approx(fit["synthetic_recall_by_bin"], abs=1e-4)
        assert max(abs(r - s) for r, s in zip(real, synthetic)) == pytest.approx(fit["largest_bin_gap"], abs=1e-4)


def test_curve_fit_recovers_a_known_logistic():
    rng = np.random.default_rng(0)
    h = rng.uniform(0, 400, 20000)
    half, slope = fit_detection_curve(h, rng.random(h.size) < logistic(h, 150.0, 20.0))
    assert half == pytest.approx(150.0, abs=3.0) and slope == pytest.approx(20.0, rel=0.1)


def test_profile_by_backend_name_and_unknown_profile():
    model = create_detector("detector-model:yolo11n-pose-single", seed=1)
    assert isinstance(model, DetectorModel) and model.half_detection_height_px == PROFILES["yolo11n-pose-single"][
        "half_detection_height_px"]
    assert DetectorModel(profile="yolo11n-pose-single", half_detection_height_px=30.0).half_detection_height_px == 30.0
    assert DetectorModel().half_detection_height_px == 25.0  # the default profile is unchanged
    with pytest.raises(ValueError, match="unknown detector-model profile 'nope'; valid: default"):
        DetectorModel(profile="nope")
