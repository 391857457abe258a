"""Storage of scenes: exact round trip and clear errors for broken folders."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.records import GroundTruth, Scene
from pedenv.synthetic import generate_scenes
from pedenv.synthetic.detector import DetectorModel
from pedenv.synthetic.storage import read_scene, write_scenes

from scene_checks import assert_scenes_equal


@pytest.fixture(scope="module")
def short_scenes():
    return generate_scenes(5, ["crowd", "turn-intersection"], duration_s=2.0, terrain=True)


def test_round_trip_is_exact(tmp_path, short_scenes):
    write_scenes(short_scenes, tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["crowd", "turn-intersection"]
    for scene in short_scenes:
        assert sorted(p.name for p in (tmp_path / scene.name).iterdir()) == ["frames.npz", "scene.json"]
        assert_scenes_equal(read_scene(tmp_path / scene.name), scene)


def test_round_trip_with_detections_missing_labels_and_image_paths(tmp_path, short_scenes):
    scene = short_scenes[0]
    model = DetectorModel(seed=1)
    frames = [replace(f, detections=model(f)) for f in scene.frames]
    gt = frames[1].ground_truth
    frames[1] = replace(frames[1], ground_truth=GroundTruth(gt.ids, gt.positions, gt.boxes))  # no skeletons
    frames[2] = replace(frames[2], ground_truth=None, image_path="images/0002.png")
    mixed = Scene("mixed", frames, "detections and gaps")
    write_scenes([mixed], tmp_path)
    back = read_scene(tmp_path / "mixed")
    assert_scenes_equal(back, mixed)
    assert back.frames[1].ground_truth.keypoints is None and back.frames[2].ground_truth is None


def test_writing_an_image_or_a_bad_name_is_refused(tmp_path, short_scenes):
    frame = replace(short_scenes[0].frames[0], image=np.zeros((900, 1600, 3), np.uint8))
    with pytest.raises(InputError, match="stores no images"):
        write_scenes([Scene("with-image", (frame,))], tmp_path)
    with pytest.raises(InputError, match="folder name"):
        write_scenes([Scene("../escape", short_scenes[0].frames)], tmp_path)


def _break(folder, how):
    if how == "no scene.json":
        (folder / "scene.json").unlink()
    elif how == "no frames.npz":
        (folder / "frames.npz").unlink()
    elif how == "bad json":
        (folder / "scene.json").write_text("{not json")
    elif how == "other format":
        (folder / "scene.json").write_text(json.dumps({"format": "carla", "version": 1}))
    elif how == "frame count":
        meta = json.loads((folder / "scene.json").read_text())
        meta["num_frames"] += 1
        (folder / "scene.json").write_text(json.dumps(meta))
    elif how == "missing array":
        with np.load(folder / "frames.npz") as data:
            arrays = {k: data[k] for k in data.files if k != "gt_boxes"}
        np.savez(folder / "frames.npz", **arrays)


@pytest.mark.parametrize("how, message", [
    ("no scene.json", "scene.json"), ("no frames.npz", "frames.npz"), ("bad json", "cannot read JSON"),
    ("other format", "expected format 'pedenv-synthetic'"), ("frame count", "scene.json says"),
    ("missing array", "missing arrays gt_boxes"),
])
def test_broken_folders_raise_input_error_naming_the_file(tmp_path, short_scenes, how, message):
    write_scenes(short_scenes[:1], tmp_path)
    folder = tmp_path / "crowd"
    _break(folder, how)
    with pytest.raises(InputError, match=message) as info:
        read_scene(folder)
    assert str(folder) in str(info.value)
