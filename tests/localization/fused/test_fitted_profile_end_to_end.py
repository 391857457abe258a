"""Seeded end-to-end run with the detector model fitted to the real network.

The built-in scenes on rolling terrain (seed 0, 8 s each) seen through the
``yolo11n-pose-far`` profile (YOLO11n-pose in the ``far`` detection mode, measured on the
real samples: benchmarks/results/detector_yolo11n-pose-far.json), the paper's method and
the fused one on the same frames. Measured with seed 0 and the profile refitted to the
rebuilt ``far`` mode (pyramid levels; recall 3 / 57 / 86 / 99 % by height bin, 0.33 false
positives per frame; ``benchmarks/fused_calibration.py --profile yolo11n-pose-far
--breakdown``): paper 15.97 % over 4351 matched detections, fused 7.39 % over 4341; fused
1-sigma coverage 0.551, 2-sigma 0.908, mean NEES 3.05 (ideal 2). The refitted profile sees
far more small people than the old one (50 % at 68 px box height instead of 102 px), hence
the larger counts. Issue 11's goals missed here: the 1-sigma coverage is above 50 % (the
core of the errors is over-covered: own-person matches have NEES 1.28) and the mean NEES is
just above 3; the excess comes from the false positives (38 matches, 42 % of the summed
error, NEES 35) and people matched to a neighbour across the ray (226 matches, NEES 30),
both under the paper's any-overlap matching rule. With the profile of the old ``far`` mode
the same run gave fused 7.88 % vs paper 16.79 % over about 2620 matches, 0.560 / 0.932,
NEES 2.36.
"""

import pytest

from pedenv.apps.compare import compare_methods
from pedenv.config import Config
from pedenv.io.datasets.memory import MemoryDataset
from pedenv.synthetic import generate_scenes


@pytest.mark.slow
def test_fused_with_the_fitted_detector_model_is_calibrated_and_beats_the_paper():
    data = MemoryDataset(generate_scenes(0, terrain=True, duration_s=8.0), name="terrain7-8s")
    results = compare_methods(data, pose_backend="detector-model:yolo11n-pose-far", config=Config())
    paper, fused = results["paper"].metrics, results["fused"].metrics
    assert paper.overall.count > 4200 and paper.overall.count - 20 <= fused.overall.count <= paper.overall.count
    assert fused.overall.rel_error_pct <= 7.8
    assert paper.overall.rel_error_pct >= 15.0
    assert fused.overall.rel_error_pct < paper.overall.rel_error_pct - 5.0
    assert 0.50 <= fused.calibration["within_1sigma"] <= 0.60
    assert fused.calibration["within_2sigma"] >= 0.88
    assert fused.calibration["mean_nees"] <= 3.3
