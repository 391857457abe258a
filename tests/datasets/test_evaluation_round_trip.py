"""Evaluating an exported set through its adapter gives the errors of evaluating the scenes directly."""

from __future__ import annotations

from dataclasses import replace

import pytest

from pedenv.apps.evaluate import evaluate_dataset
from pedenv.datasets.carla import CarlaDataset
from pedenv.datasets.carla_export import write_carla
from pedenv.datasets.memory import MemoryDataset
from pedenv.datasets.nuscenes_export import KEYFRAME_EVERY, write_nuscenes
from pedenv.pose.ground_truth import GroundTruthPose
from pedenv.records import Scene
from pedenv.synthetic import generate_scenes


def _labelled_on_keyframes(scene: Scene) -> Scene:
    """The scene as nuScenes holds it: up to its last keyframe, labels on every 6th frame only,
    the other frames with their exact skeletons as detections."""
    n = (len(scene) - 1) // KEYFRAME_EVERY * KEYFRAME_EVERY + 1
    backend = GroundTruthPose()
    frames = [f if i % KEYFRAME_EVERY == 0 else replace(f, ground_truth=None, detections=backend(f))
              for i, f in enumerate(scene.frames[:n])]
    return Scene(scene.name, tuple(frames))


def _assert_same(a: dict, b: dict) -> None:
    assert a["overall"]["count"] == b["overall"]["count"] > 0
    assert a["overall"]["abs_error_m"] == pytest.approx(b["overall"]["abs_error_m"], abs=1e-4)
    assert a["overall"]["rel_error_pct"] == pytest.approx(b["overall"]["rel_error_pct"], abs=1e-3)
    for sa, sb in zip(a["scenes"], b["scenes"]):
        assert sa["count"] == sb["count"]
        if sa["count"]:
            assert sa["abs_error_m"] == pytest.approx(sb["abs_error_m"], abs=1e-4)


@pytest.mark.nuscenes
@pytest.mark.slow
def test_nuscenes_export_evaluates_like_the_scenes(tmp_path):
    from pedenv.datasets.nuscenes import NuScenesDataset

    scenes = generate_scenes(3, ["red-light-crossing", "turn-intersection"], frame_rate_hz=12, duration_s=6)
    scenes = [replace(s, name=f"scene-{i + 1:04d}") for i, s in enumerate(scenes)]
    write_nuscenes(scenes, tmp_path)
    through_adapter = evaluate_dataset(NuScenesDataset(tmp_path), pose_backend="ground-truth").to_dict()
    direct = evaluate_dataset(MemoryDataset([_labelled_on_keyframes(s) for s in scenes]),
                              pose_backend="ground-truth").to_dict()
    _assert_same(through_adapter, direct)


@pytest.mark.slow
def test_carla_export_evaluates_close_to_the_scenes(tmp_path):
    """The CARLA layout keeps positions and joints exactly but not everything: the nose becomes the
    head's centre, ears and occlusion flags are lost (every in-image keypoint counts as seen). So the
    errors through the adapter are close to, not equal to, those of the scenes (measured: 6.45 m vs
    6.90 m, 3185 vs 3183 matches on these two scenes)."""
    scenes = generate_scenes(3, ["red-light-crossing", "turn-intersection"], frame_rate_hz=10, duration_s=6)
    write_carla(scenes, tmp_path)
    through_adapter = evaluate_dataset(CarlaDataset(tmp_path)).to_dict()  # default backend: ground-truth
    direct = evaluate_dataset(MemoryDataset(scenes), pose_backend="ground-truth").to_dict()
    a, b = through_adapter["overall"], direct["overall"]
    assert a["count"] == pytest.approx(b["count"], rel=0.01) and a["count"] > 1000
    assert a["abs_error_m"] == pytest.approx(b["abs_error_m"], rel=0.15)
    assert a["rel_error_pct"] == pytest.approx(b["rel_error_pct"], rel=0.15)
