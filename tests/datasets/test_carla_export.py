"""The CARLA writer, read back by the CARLA reader."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.datasets import scene_writer
from pedenv.datasets.carla import CarlaDataset, load_record
from pedenv.datasets.carla_bones import EXACT_KEYPOINTS
from pedenv.datasets.carla_export import write_carla
from pedenv.errors import InputError
from pedenv.records import GroundTruth, Scene


@pytest.fixture
def written(tmp_path, scene_factory):
    scenes = [scene_factory("walk", n_frames=12, rate_hz=10.0, t0=3.0),
              scene_factory("turn", n_frames=8, rate_hz=10.0, yaw_rate=-0.3)]
    folders = scene_writer("carla")(scenes, tmp_path)
    return scenes, folders, tmp_path


def test_layout(written):
    scenes, folders, root = written
    assert [f.name for f in folders] == ["scene0", "scene1"]
    numbers = sorted(int(p.stem.split("_")[1]) for p in (root / "scene0" / "data").glob("data_*.npy"))
    assert numbers[0] > 0 and numbers == list(range(numbers[0], numbers[0] + 12))
    assert (root / "scene0" / "rgb" / f"img_{numbers[0]}.png").is_file()
    record = load_record(root / "scene0" / "data" / f"data_{numbers[0]}.npy")
    np.testing.assert_allclose(record["world2cam"] @ record["cam2world"], np.eye(4), atol=1e-12)
    assert record["2d_skel"][0].shape == (20, 2) and record["3d_skel"][0].shape == (20, 3)
    u, v = np.concatenate(record["2d_skel"]).T
    assert u.min() >= 0 and u.max() <= 1599 and v.min() >= 0 and v.max() <= 899
    # Unreal axes: the camera's local x (first column) looks along the vehicle's heading, y flipped
    frame = scenes[0].frames[0]
    forward_ours = frame.cam_to_world[:3, 2]
    np.testing.assert_allclose(record["cam2world"][:3, 0], forward_ours * [1, -1, 1], atol=1e-12)


def test_round_trip(written):
    scenes, folders, root = written
    ds = CarlaDataset(root)
    assert ds.scene_names() == ["scene0", "scene1"]
    for scene, name in zip(scenes, ds.scene_names()):
        frames = list(ds.frames(name))
        assert len(frames) == len(scene)
        for ours, back in zip(scene.frames, frames):
            assert back.timestamp == pytest.approx(ours.timestamp - scene.frames[0].timestamp, abs=1e-9)
            np.testing.assert_allclose(back.ego.matrix, ours.ego.matrix, atol=1e-9)
            np.testing.assert_allclose(back.cam_to_world, ours.cam_to_world, atol=1e-9)
            np.testing.assert_allclose(back.camera.intrinsics, ours.camera.intrinsics)
            assert (back.camera.width, back.camera.height) == (ours.camera.width, ours.camera.height)
            a, b = ours.ground_truth, back.ground_truth
            np.testing.assert_allclose(b.positions, a.positions, atol=1e-6)
            np.testing.assert_allclose(
                b.keypoints_3d[:, EXACT_KEYPOINTS], a.keypoints_3d[:, EXACT_KEYPOINTS], atol=1e-6
            )
            seen = a.visible[:, EXACT_KEYPOINTS]
            np.testing.assert_allclose(
                b.keypoints[:, EXACT_KEYPOINTS][seen], a.keypoints[:, EXACT_KEYPOINTS][seen], atol=1e-6
            )
            assert np.all(b.visible[:, EXACT_KEYPOINTS][seen])
            np.testing.assert_array_equal(b.ids, -1)


def test_scene_names_kept_when_carla_like(tmp_path, scene_factory):
    folders = write_carla([scene_factory("scene7", n_frames=2, rate_hz=10.0)], tmp_path, first_frame=500)
    assert folders[0].name == "scene7"
    assert (tmp_path / "scene7" / "data" / "data_501.npy").is_file()


def test_not_10_hz_is_an_error(tmp_path, scene_factory):
    with pytest.raises(InputError, match=r"scene 'a' frame 1: .* not on the 10 Hz grid"):
        write_carla([scene_factory("a", n_frames=3, rate_hz=12.0)], tmp_path)


def test_ground_truth_without_3d_skeletons_is_an_error(tmp_path, scene_factory):
    scene = scene_factory("a", n_frames=2, rate_hz=10.0)
    f = scene.frames[1]
    gt = f.ground_truth
    flat = GroundTruth(gt.ids, gt.positions, gt.boxes, gt.keypoints, gt.visible)
    bad = Scene("a", (scene.frames[0], type(f)(**{**f.__dict__, "ground_truth": flat})))
    with pytest.raises(InputError, match="scene 'a' frame 1: ground truth has no keypoints_3d"):
        write_carla([bad], tmp_path)


def test_empty_frames_are_written(tmp_path, scene_factory):
    scene = scene_factory("a", n_frames=2, rate_hz=10.0)
    f = scene.frames[1]
    empty = Scene("a", (scene.frames[0], type(f)(**{**f.__dict__, "ground_truth": None})))
    write_carla([empty], tmp_path)
    frames = list(CarlaDataset(tmp_path).frames("scene0"))
    assert len(frames[1].ground_truth) == 0
