"""The nuScenes export, loaded by the official devkit."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pedenv.datasets import scene_writer
from pedenv.datasets.nuscenes_export import KEYFRAME_EVERY, write_nuscenes
from pedenv.datasets.nuscenes_skeletons import SIDE_FILE_NAME, read_side_file

pytestmark = pytest.mark.nuscenes


@pytest.fixture(scope="module")
def exported(tmp_path_factory, scene_factory):
    make_scene = scene_factory
    root = tmp_path_factory.mktemp("nuscenes")
    scenes = [make_scene("scene-0001", n_frames=25), make_scene("walk", n_frames=21, yaw_rate=-0.2, t0=100.0)]
    scene_writer("nuscenes")(scenes, root)
    from nuscenes.nuscenes import NuScenes

    return scenes, root, NuScenes(version="v1.0-mini", dataroot=str(root), verbose=False)


def test_tables_and_counts(exported):
    scenes, root, nusc = exported
    assert [s["name"] for s in nusc.scene] == ["scene-0001", "scene-0002"]
    assert nusc.scene[1]["description"] == "walk"
    assert [s["nbr_samples"] for s in nusc.scene] == [5, 4]  # 25 frames -> 0,6,..,24; 21 -> 0..18 (2 trailing dropped)
    assert len(nusc.sample) == 9 and len(nusc.sample_data) == 25 + 19 and len(nusc.ego_pose) == 44
    assert len(nusc.log) == 2 and set(nusc.map[0]["log_tokens"]) == {r["token"] for r in nusc.log}
    assert (root / nusc.map[0]["filename"]).is_file()
    cs = nusc.calibrated_sensor[0]
    np.testing.assert_allclose(cs["rotation"], [0.5, -0.5, 0.5, -0.5], atol=1e-12)
    np.testing.assert_allclose(cs["translation"], [1.7, 0.0, 1.5])


def test_chains_and_keyframe_cadence(exported):
    scenes, root, nusc = exported
    for scene_rec, _scene in zip(nusc.scene, scenes):
        sample = nusc.get("sample", scene_rec["first_sample_token"])
        sd = nusc.get("sample_data", sample["data"]["CAM_FRONT"])
        assert sd["prev"] == ""
        chain = [sd]
        while sd["next"]:
            sd = nusc.get("sample_data", sd["next"])
            chain.append(sd)
        keys = [i for i, r in enumerate(chain) if r["is_key_frame"]]
        assert keys == list(range(0, len(chain), KEYFRAME_EVERY)) and keys[-1] == len(chain) - 1
        stamps = np.array([r["timestamp"] for r in chain])
        np.testing.assert_allclose(np.diff(stamps), 1e6 / 12, atol=1)
        for i, r in enumerate(chain):
            next_key = chain[-(-i // KEYFRAME_EVERY) * KEYFRAME_EVERY]
            assert r["sample_token"] == next_key["sample_token"]
            assert nusc.get("ego_pose", r["ego_pose_token"])["timestamp"] == r["timestamp"]
            folder = "samples" if r["is_key_frame"] else "sweeps"
            assert r["filename"].startswith(f"{folder}/CAM_FRONT/") and (root / r["filename"]).stat().st_size > 1000
        samples = [nusc.get("sample", r["sample_token"]) for r in chain if r["is_key_frame"]]
        assert all(s["scene_token"] == scene_rec["token"] for s in samples)
        assert (
            samples[0]["prev"] == ""
            and samples[-1]["next"] == ""
            and samples[-1]["token"] == scene_rec["last_sample_token"]
        )


def test_annotations_and_instances(exported):
    scenes, root, nusc = exported
    for inst in nusc.instance:
        anns = [nusc.get("sample_annotation", inst["first_annotation_token"])]
        while anns[-1]["next"]:
            anns.append(nusc.get("sample_annotation", anns[-1]["next"]))
        assert len(anns) == inst["nbr_annotations"] and anns[-1]["token"] == inst["last_annotation_token"]
        times = [nusc.get("sample", a["sample_token"])["timestamp"] for a in anns]
        assert times == sorted(times)
    for ann in nusc.sample_annotation:
        assert ann["category_name"] == "human.pedestrian.adult" and ann["num_lidar_pts"] > 0
        assert len(ann["size"]) == 3 and ann["visibility_token"] in {"1", "2", "3", "4"}
        assert len(ann["attribute_tokens"]) == 1
    # the keyframe at t = 0.5 s of scene-0001 holds the ground truth of frame 6
    gt = scenes[0].frames[6].ground_truth
    sample = nusc.get("sample", nusc.scene[0]["first_sample_token"])
    sample = nusc.get("sample", sample["next"])
    centres = np.array([nusc.get("sample_annotation", a)["translation"] for a in sample["anns"]])
    np.testing.assert_allclose(centres, gt.positions + [0, 0, 1.75 / 2], atol=1e-12)


def test_side_file(exported):
    scenes, root, nusc = exported
    side = read_side_file(root / SIDE_FILE_NAME)
    assert set(side) == {r["token"] for r in nusc.sample_data}
    sd = nusc.get("sample_data", nusc.get("sample", nusc.scene[0]["first_sample_token"])["data"]["CAM_FRONT"])
    np.testing.assert_array_equal([s.keypoints for s in side[sd["token"]]], scenes[0].frames[0].ground_truth.keypoints)
    data = json.loads((root / SIDE_FILE_NAME).read_text())
    assert data["format"] == "pedenv-skeletons" and data["layout"] == "coco-17"


def test_bad_options(tmp_path, scene_factory):
    make_scene = scene_factory
    with pytest.raises(ValueError, match="jpeg_quality"):
        write_nuscenes([make_scene(n_frames=2)], tmp_path, jpeg_quality=0)
    with pytest.warns(UserWarning, match="runs at 10.0 Hz, not 12 Hz"):
        write_nuscenes([make_scene(n_frames=7, rate_hz=10.0)], tmp_path)
