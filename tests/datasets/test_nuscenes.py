"""The nuScenes adapter (on the official devkit) reading back an exported set, and its bad input."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from pedenv.datasets import open_dataset
from pedenv.datasets.nuscenes import PAPER_SCENES, NuScenesDataset
from pedenv.datasets.nuscenes_export import KEYFRAME_EVERY, write_nuscenes
from pedenv.datasets.nuscenes_skeletons import SIDE_FILE_NAME
from pedenv.errors import InputError
from pedenv.pose.ground_truth import GroundTruthPose

pytestmark = pytest.mark.nuscenes


@pytest.fixture(scope="module")
def exported(tmp_path_factory, scene_factory):
    root = tmp_path_factory.mktemp("nuscenes")
    scenes = [scene_factory("scene-0001", n_frames=25), scene_factory("scene-0042", n_frames=13, yaw_rate=-0.2, t0=7.0)]
    write_nuscenes(scenes, root)
    return scenes, root, NuScenesDataset(root)


def test_scenes_and_frames(exported):
    scenes, root, ds = exported
    assert ds.name == "nuscenes" and ds.default_pose_backend == "onnx"
    assert ds.scene_names() == ["scene-0001", "scene-0042"]
    assert isinstance(open_dataset("nuscenes", root), NuScenesDataset)
    for scene in scenes:
        frames = list(ds.frames(scene.name))
        assert len(frames) == len(scene) and [f.index for f in frames] == list(range(len(scene)))
        for i, (ours, back) in enumerate(zip(scene.frames, frames)):
            assert back.scene == scene.name and back.image_path.is_file()
            assert back.timestamp == pytest.approx(ours.timestamp, abs=1e-6)
            np.testing.assert_allclose(back.ego.matrix, ours.ego.matrix, atol=1e-9)
            np.testing.assert_allclose(back.camera.cam_to_vehicle, ours.camera.cam_to_vehicle, atol=1e-9)
            np.testing.assert_allclose(back.camera.intrinsics, ours.camera.intrinsics)
            assert (back.camera.width, back.camera.height) == (1600, 900)
            assert (back.ground_truth is not None) == (i % KEYFRAME_EVERY == 0)


def test_ground_truth_round_trip(exported):
    scenes, root, ds = exported
    ids_seen: dict[int, tuple] = {}  # one instance per (scene, id)
    for scene in scenes:
        for ours, back in zip(scene.frames, ds.frames(scene.name)):
            if back.ground_truth is None:
                dets = back.detections
                keep = ours.ground_truth.visible.any(axis=1)
                np.testing.assert_allclose(dets.keypoints, ours.ground_truth.keypoints[keep], atol=1e-9)
                np.testing.assert_array_equal(dets.confidences, ours.ground_truth.visible[keep].astype(float))
                continue
            a, b = ours.ground_truth, back.ground_truth
            assert len(a) == len(b)
            np.testing.assert_allclose(b.positions, a.positions, atol=1e-3)
            np.testing.assert_allclose(b.boxes, a.boxes, atol=1e-9)
            np.testing.assert_allclose(b.keypoints, a.keypoints, atol=1e-9)
            np.testing.assert_array_equal(b.visible, a.visible)
            np.testing.assert_allclose(b.heights, 1.75)
            for old, new in zip(a.ids, b.ids):  # instance tokens -> stable ints, one to one
                assert ids_seen.setdefault(int(new), (scene.name, int(old))) == (scene.name, old)
    assert len(ids_seen) == len(set(ids_seen.values()))


def test_ground_truth_backend_works_on_every_frame(exported):
    scenes, root, ds = exported
    backend = GroundTruthPose()
    counts = [len(backend(f)) for f in ds.frames("scene-0001")]
    assert min(counts) >= 3


def test_box_projection_without_side_file(exported, tmp_path):
    """Without skeletons the 2D box is the projected 3D box, clipped to the image, around the skeleton box."""
    scenes, root, _ = exported
    plain = tmp_path / "plain"
    shutil.copytree(root / "v1.0-mini", plain / "v1.0-mini")
    shutil.copytree(root / "maps", plain / "maps")
    ds = NuScenesDataset(plain)
    with pytest.warns(UserWarning, match=r"image .*scene-0001__CAM_FRONT__0\.jpg is missing"):
        frame = next(ds.frames("scene-0001"))
    gt, ours = frame.ground_truth, scenes[0].frames[0].ground_truth
    assert gt.keypoints is None and frame.detections is None
    assert np.all(gt.boxes[:, :2] <= ours.boxes[:, :2] + 1) and np.all(gt.boxes[:, 2:] >= ours.boxes[:, 2:] - 1)
    assert np.all(gt.boxes[:, 0] >= 0) and np.all(gt.boxes[:, 2] <= 1600)


def test_pedestrian_behind_camera_is_not_ground_truth(exported, tmp_path):
    scenes, root, _ = exported
    copy = tmp_path / "copy"
    shutil.copytree(root, copy)
    path = copy / "v1.0-mini" / "sample_annotation.json"
    anns = json.loads(path.read_text())
    first_sample = anns[0]["sample_token"]
    anns[0]["translation"][0] = -30.0  # far behind the ego
    path.write_text(json.dumps(anns))
    gt = next(NuScenesDataset(copy).frames("scene-0001")).ground_truth
    assert anns[0]["sample_token"] == first_sample and len(gt) == len(scenes[0].frames[0].ground_truth) - 1


def test_paper_scenes_are_the_default(exported, tmp_path):
    scenes, root, _ = exported
    assert PAPER_SCENES[0] == "scene-0061" and len(PAPER_SCENES) == 7
    copy = tmp_path / "copy"
    shutil.copytree(root / "v1.0-mini", copy / "v1.0-mini")
    shutil.copytree(root / "maps", copy / "maps")
    path = copy / "v1.0-mini" / "scene.json"
    recs = json.loads(path.read_text())
    recs[1]["name"] = "scene-0553"
    path.write_text(json.dumps(recs))
    ds = NuScenesDataset(copy)
    assert ds.default_scenes() == ["scene-0553"]
    assert ds.scene_names() == ["scene-0001", "scene-0553"]  # every scene can still be named


def test_bad_input(exported, tmp_path):
    scenes, root, ds = exported
    with pytest.raises(InputError, match="does not exist or is not a folder"):
        NuScenesDataset(tmp_path / "nowhere")
    with pytest.raises(InputError, match=r"v1\.0-trainval does not exist; version folders here: v1\.0-mini"):
        NuScenesDataset(root, version="v1.0-trainval")
    broken = tmp_path / "broken"
    shutil.copytree(root / "v1.0-mini", broken / "v1.0-mini")
    (broken / "v1.0-mini" / "ego_pose.json").unlink()
    (broken / "v1.0-mini" / "map.json").unlink()
    with pytest.raises(InputError, match=r"missing nuScenes table\(s\) ego_pose\.json, map\.json"):
        NuScenesDataset(broken)
    with pytest.raises(InputError, match="the nuScenes devkit cannot load"):  # tables without the map PNG
        shutil.copytree(root / "v1.0-mini", tmp_path / "nomap" / "v1.0-mini")
        NuScenesDataset(tmp_path / "nomap")
    with pytest.raises(InputError, match=r"unknown nuScenes scene 'scene-0061'.*valid: scene-0001, scene-0042"):
        list(ds.frames("scene-0061"))
    with pytest.raises(InputError, match="skeleton side file .* does not exist"):
        NuScenesDataset(root, skeletons=tmp_path / "none.json")
    bad_side = tmp_path / "side.json"
    bad_side.write_text(json.dumps({"format": "pedenv-skeletons", "sample_data": {"t": [{"instance_token": "x"}]}}))
    with pytest.raises(
        InputError, match=r"side\.json: sample_data t entry 0: needs instance_token, keypoints, visible"
    ):
        NuScenesDataset(root, skeletons=bad_side)
    assert (root / SIDE_FILE_NAME).is_file()


@pytest.mark.parametrize("table, field, value, message", [
    ("ego_pose", "rotation", [0.0, 0.0, 0.0, 0.0], "a zero quaternion"),
    ("ego_pose", "translation", [float("nan"), 0.0, 0.0], "ego translation contains NaN or inf"),
    ("calibrated_sensor", "camera_intrinsic", [[0.0, 0, 0], [0, 0, 0], [0, 0, 1]], "intrinsics must be an invertible"),
])
def test_nan_and_zero_table_values_name_the_tables(exported, tmp_path, table, field, value, message):
    """Issue 10.8: NaN or zero values in the tables gave messages naming no file."""
    scenes, root, ds = exported
    copy = tmp_path / "copy"
    shutil.copytree(root, copy)
    path = copy / "v1.0-mini" / f"{table}.json"
    records = json.loads(path.read_text())
    for record in records:
        record[field] = value
    path.write_text(json.dumps(records))  # json writes NaN as the token NaN, as a broken export might
    with pytest.raises(InputError, match=r"v1\.0-mini: scene scene-0001, frame 0 \(sample_data .*\): .*" + message):
        next(NuScenesDataset(copy).frames("scene-0001"))
