"""Seeded end-to-end run with the detector model fitted to the real network.

The built-in scenes on rolling terrain (seed 0, 8 s each) seen through the
``yolo11n-pose-far`` profile (YOLO11n-pose in the ``far`` detection mode, measured on the
real samples: benchmarks/results/detector_yolo11n-pose-far.json), the paper's method and
the fused one on the same frames. The profile's detection curve follows the ``far`` mode
(pyramid levels; recall 5 / 70 / 87 / 99 % by height bin on the real samples, 0.31 false
positives per frame) and each person's skeleton carries the persistent offset the real
network showed against the KITTI and nuScenes 3D truth (``person_offset_u/v``: 3.5 % and
2.3 % of the box height across persons, where the synthetic skeletons alone had 1.1 / 1.2 %).

Measured with seed 0 (``benchmarks/fused_calibration.py --profile yolo11n-pose-far
--breakdown``): paper 15.55 % over 5087 matched detections, fused 6.75 % over 5077; fused
1-sigma coverage 0.358, 2-sigma 0.824, mean NEES 2.35 (ideal 0.393, 0.865, 2), each
covariance judged against its own person (one-to-one, box IoU >= 0.5); ID switches 369
(fused) against 948 (the paper's tracker). Without the person offsets (the profile before,
fitted to an older ``far``) the skeletons were cleaner than the real network's and the run
gave fused 7.39 %, 0.565 / 0.942, NEES 1.40: over-covered. Under the paper's nearest-truth
matching the coverage is about the same and the NEES 3.78, from false positives (41
matches, NEES 30) and estimates scored against a neighbour (258 matches, NEES 28).
"""

import pytest

from pedenv.apps.compare import compare_methods
from pedenv.config import Config
from pedenv.datasets.memory import MemoryDataset
from pedenv.synthetic import generate_scenes


@pytest.mark.slow
def test_fused_with_the_fitted_detector_model_is_calibrated_and_beats_the_paper():
    data = MemoryDataset(generate_scenes(0, terrain=True, duration_s=8.0), name="terrain7-8s")
    results = compare_methods(data, pose_backend="detector-model:yolo11n-pose-far", config=Config())
    paper, fused = results["paper"].metrics, results["fused"].metrics
    assert paper.overall.count > 5000 and paper.overall.count - 20 <= fused.overall.count <= paper.overall.count
    assert fused.overall.rel_error_pct <= 7.2
    assert paper.overall.rel_error_pct >= 15.0
    assert fused.overall.rel_error_pct < paper.overall.rel_error_pct - 5.0
    assert 0.32 <= fused.calibration["within_1sigma"] <= 0.42
    assert fused.calibration["within_2sigma"] >= 0.79
    assert 1.6 <= fused.calibration["mean_nees"] <= 2.9
    assert results["fused"].metrics.tracking["id_switches"] <= 0.5 * results["paper"].metrics.tracking["id_switches"]
