"""The detection benchmark on the real samples (CI): recall minima measured with the shipped model.

The minima are the recall measured on 2026-11-22 (see the report in the README's
detection table) less a small margin; timings are printed by the command, never asserted.
"""

import json

import cv2
import numpy as np
import pytest
from typer.testing import CliRunner

from pedenv.cli import app

from shared_paths import REAL_SAMPLES

pytestmark = [pytest.mark.onnx_model, pytest.mark.ultralytics, pytest.mark.slow]

#: mode -> (overall recall, recall >= 80 px, recall 40-80 px, precision): measured 2026-11-22
#: (fast 0.175, 0.225, 0.00, 0.981) and 2026-11-23 (far, the pyramid with its rows fitted to
#: people scoring >= 0.35: 0.808, 0.911, 0.527, 0.939, strict precision 0.896) minus 3 points;
#: far with the cascade for small people, 2026-11-24: 0.832, 0.911, 0.652, 0.904, minus 3 points;
#: stream (each sequence's samples in order, budget 3 units), 2026-11-24: 0.569, 0.665, 0.277, 0.944;
#: 2026-11-25 (denser track crops, the budget's leftover to the tracks): 0.711, 0.815, 0.411, 0.960, minus 3 points.
MINIMA = {
    "fast": (0.14, 0.19, 0.0, 0.95),
    "far": (0.80, 0.88, 0.62, 0.87),
    "stream": (0.68, 0.78, 0.38, 0.93),
}


@pytest.fixture(scope="module")
def model_cache(tmp_path_factory):
    from pedenv.pose.models import prepare_models

    cache = tmp_path_factory.mktemp("pedenv-cache")
    prepare_models(cache=cache)
    return cache


@pytest.mark.parametrize("mode", ["fast", "far", "stream"])
def test_benchmark_recall_on_the_real_samples(mode, model_cache, tmp_path, monkeypatch):
    monkeypatch.setenv("PEDENV_CACHE", str(model_cache))
    result = CliRunner().invoke(app, ["evaluate-detections", "--data-root", str(REAL_SAMPLES), "--detection", mode,
                                      "--output", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "recall by distance" in result.stdout
    report = json.loads((tmp_path / "detections_eval.json").read_text())
    block = report["summary"]["all"]
    goals = {b["bin"]: b["recall"] for b in block["by_goal_height"]}
    recall, big, small, precision = MINIMA[mode]
    assert block["persons"] == 578
    assert block["recall"] >= recall and goals[">=80"] >= big and goals["40-80"] >= small
    assert block["precision"] >= precision
    print(mode, block["recall"], goals, block["precision"], block["ms_per_frame"])


@pytest.mark.parametrize("shape", [(100, 100), (6000, 8000), (40, 3000)])
def test_far_on_tiny_and_huge_images_does_not_crash(shape, model_cache, monkeypatch):
    monkeypatch.setenv("PEDENV_CACHE", str(model_cache))
    from pedenv.detection import create_detector
    from pedenv.detection.geometry import CameraGeometry

    image = np.full((*shape, 3), 120, np.uint8)
    cv2.circle(image, (shape[1] // 2, shape[0] // 2), min(shape) // 4, (30, 60, 200), -1)
    pose = create_detector("onnx", detection="far")
    dets = pose.detect(image)
    assert len(dets) == 0 or (dets.boxes[:, 2] <= shape[1] + 1e-6).all()
    sky = CameraGeometry.level(np.array([[800, 0, shape[1] / 2], [0, 800, shape[0] / 2], [0, 0, 1]]), 1.5,
                               pitch_down_rad=-1.2)
    assert len(pose.detect(image, sky)) >= 0
    assert "no usable calibration" in pose.plan(shape[1], shape[0], sky)[1]


def test_detection_mode_is_checked(model_cache, monkeypatch):
    monkeypatch.setenv("PEDENV_CACHE", str(model_cache))
    from pedenv.detection import create_detector

    with pytest.raises(ValueError, match="detection mode must be one of fast, far"):
        create_detector("onnx", detection="medium")
    fast = create_detector("onnx", detection="fast")
    assert fast.describe()["detection"]["mode"] == "fast" and fast.network.dynamic
