"""The CARLA reader against the independently generated recording in shared/samples."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from pedenv.datasets import open_dataset
from pedenv.datasets.carla import CarlaDataset, load_record, natural_key
from pedenv.datasets.carla_axes import carla_rotation, carla_ypr, ego_from_unreal, ego_to_unreal
from pedenv.datasets.carla_bones import BONE_NAMES, bones_to_coco
from pedenv.errors import InputError
from pedenv.geometry import invert_transform, project
from pedenv.records import OPTICAL_TO_VEHICLE
from pedenv.skeleton import CocoKeypoint as K

from shared_paths import SHARED

SAMPLES = SHARED / "samples" / "carla-recording"


@pytest.fixture(scope="module")
def sample_frames():
    ds = CarlaDataset(SAMPLES)
    return {scene: list(ds.frames(scene)) for scene in ds.scene_names()}


def test_scenes_and_timestamps(sample_frames):
    assert list(sample_frames) == ["scene1", "scene2"]
    for frames in sample_frames.values():
        assert len(frames) == 60
        np.testing.assert_allclose([f.timestamp for f in frames], np.arange(60) / 10.0, atol=1e-12)
        assert [f.index for f in frames] == list(range(60))
        assert frames[0].image_path.name.startswith("img_") and frames[0].image_path.is_file()
    ds = open_dataset("carla", SAMPLES)
    assert ds.name == "carla" and ds.default_pose_backend == "ground-truth"


def test_bones_project_onto_recorded_pixels(sample_frames):
    """Converted 3D bones through our camera land on the generator's 2D skeletons (0.2 px noise)."""
    residuals = []
    for frames in sample_frames.values():
        for f in frames:
            gt = f.ground_truth
            uv, depth = project(gt.keypoints_3d, f.camera.intrinsics, invert_transform(f.cam_to_world))
            assert np.all(depth[gt.visible] > 0)
            residuals.append((uv - gt.keypoints)[gt.visible])
    r = np.concatenate(residuals)
    assert len(r) > 10000
    assert np.abs(r).max() < 1.0
    assert np.sqrt((r ** 2).mean()) < 0.25


def test_camera_mount_and_ground_points(sample_frames):
    """The camera sits 0.6 m ahead and 1.5 m up, looking ahead; pos_3d lies just under the feet."""
    for frames in sample_frames.values():
        for f in frames:
            mount = f.camera.cam_to_vehicle
            np.testing.assert_allclose(mount[:3, 3], [0.6, 0.0, 1.5], atol=1e-9)
            np.testing.assert_allclose(mount[:3, :3], OPTICAL_TO_VEHICLE, atol=1e-9)
            gt = f.ground_truth
            ankles = gt.keypoints_3d[:, [K.LEFT_ANKLE, K.RIGHT_ANKLE]]
            assert np.all(np.linalg.norm(ankles[..., :2].mean(1) - gt.positions[:, :2], axis=1) < 0.5)
            assert np.all(
                (ankles[..., 2].min(1) - gt.positions[:, 2] > 0.0) & (ankles[..., 2].min(1) - gt.positions[:, 2] < 0.2)
            )
            np.testing.assert_array_equal(gt.ids, -1)


def test_ego_turns_right_in_scene1(sample_frames):
    """Scene 1 turns right: our yaw (counter-clockwise positive) decreases, the rotation stays proper."""
    yaws = np.array([f.ego.yaw for f in sample_frames["scene1"]])
    assert yaws[-1] < np.radians(-10) and np.all(np.diff(yaws) <= 1e-12)
    for f in sample_frames["scene1"]:
        assert np.linalg.det(f.ego.rotation) == pytest.approx(1.0)


def test_bone_mapping_left_right(sample_frames):
    """The person's own left: (left - right) points along up x facing, facing = from head to eyes."""
    agree = total = 0
    for frames in sample_frames.values():
        for f in frames:
            k = f.ground_truth.keypoints_3d
            facing = 0.5 * (k[:, K.LEFT_EYE] + k[:, K.RIGHT_EYE]) - k[:, K.NOSE]
            left = np.cross([0.0, 0.0, 1.0], facing)
            for a, b in ((K.LEFT_SHOULDER, K.RIGHT_SHOULDER), (K.LEFT_HIP, K.RIGHT_HIP), (K.LEFT_EYE, K.RIGHT_EYE)):
                agree += int(np.sum(np.sum(left * (k[:, a] - k[:, b]), axis=1) > 0))
                total += len(k)
    assert total > 0 and agree == total


def test_bone_mapping_and_visibility(sample_frames):
    record = load_record(SAMPLES / "scene1" / "data" / "data_18231.npy")
    f = sample_frames["scene1"][0]
    bones = np.asarray(record["2d_skel"])
    np.testing.assert_array_equal(f.ground_truth.keypoints, bones_to_coco(bones))
    np.testing.assert_array_equal(f.ground_truth.keypoints[:, K.NOSE], bones[:, BONE_NAMES.index("head")])
    np.testing.assert_array_equal(f.ground_truth.keypoints[:, K.LEFT_ANKLE], bones[:, BONE_NAMES.index("foot_L")])
    np.testing.assert_array_equal(f.ground_truth.boxes, np.asarray(record["bbox_2d"]))
    all_vis = np.concatenate([fr.ground_truth.visible for frames in sample_frames.values() for fr in frames])
    all_kp = np.concatenate([fr.ground_truth.keypoints for frames in sample_frames.values() for fr in frames])
    assert not all_vis[:, [K.LEFT_EAR, K.RIGHT_EAR]].any()
    on_border = (all_kp[..., 0] <= 0) | (all_kp[..., 0] >= 1599)
    assert on_border.any() and not all_vis[on_border].any()
    assert all_vis[:, [K.NOSE, K.LEFT_ANKLE]][~on_border[:, [K.NOSE, K.LEFT_ANKLE]]].all()


@pytest.mark.parametrize("ypr", [(0.0, 0.0, 0.0), (16.0, -1.9, 0.0), (-130.0, 7.0, 3.0), (95.0, -20.0, -11.0)])
def test_ego_conversion_round_trip(ypr):
    xyz = np.array([1.0, -2.0, 0.3])
    m = ego_from_unreal(xyz, ypr)
    back_xyz, back_ypr = ego_to_unreal(m)
    np.testing.assert_allclose(back_xyz, xyz, atol=1e-12)
    np.testing.assert_allclose(back_ypr, ypr, atol=1e-9)
    np.testing.assert_allclose(carla_ypr(carla_rotation(*ypr)), ypr, atol=1e-9)
    # yaw only: a positive (clockwise) Unreal yaw is a negative yaw in our frame
    assert np.degrees(np.arctan2(*ego_from_unreal(xyz, (ypr[0], 0, 0))[[1, 0], 0])) == pytest.approx(-ypr[0])


@pytest.mark.parametrize("ypr", [(16.0, -1.9, 0.0), (-130.0, 7.0, 3.0), (95.0, -20.0, -11.0), (0.0, 89.0, 45.0)])
def test_carla_rotation_is_carlas_get_matrix(ypr):
    """The matrix carla.Transform.get_matrix() writes out entry by entry."""
    y, p, r = np.radians(ypr)
    cy, sy, cp, sp, cr, sr = np.cos(y), np.sin(y), np.cos(p), np.sin(p), np.cos(r), np.sin(r)
    carla = np.array([[cp * cy, cy * sp * sr - sy * cr, -cy * sp * cr - sy * sr],
                      [sy * cp, sy * sp * sr + cy * cr, -sy * sp * cr + cy * sr],
                      [sp, -cp * sr, cp * cr]])
    np.testing.assert_allclose(carla_rotation(*ypr), carla, atol=1e-15)


def test_natural_scene_order(tmp_path):
    for name in ("scene10", "scene2", "scene1"):
        shutil.copytree(SAMPLES / "scene2", tmp_path / name)
    assert CarlaDataset(tmp_path).scene_names() == ["scene1", "scene2", "scene10"]
    assert sorted(["scene10", "scene2"], key=natural_key) == ["scene2", "scene10"]


def test_gap_is_elapsed_time_with_warning(tmp_path):
    shutil.copytree(SAMPLES / "scene2", tmp_path / "scene2")
    (tmp_path / "scene2" / "data" / "data_910.npy").unlink()
    with pytest.warns(UserWarning, match=r"data_909\.npy.*data_911\.npy"):
        frames = list(CarlaDataset(tmp_path).frames("scene2"))
    assert len(frames) == 59
    assert frames[2].timestamp == pytest.approx(0.2) and frames[3].timestamp == pytest.approx(0.4)


def test_missing_image_warns_and_frame_still_usable(tmp_path):
    shutil.copytree(SAMPLES / "scene2", tmp_path / "scene2")
    (tmp_path / "scene2" / "rgb" / "img_907.png").unlink()
    with pytest.warns(UserWarning, match=r"img_907\.png"):
        frames = list(CarlaDataset(tmp_path).frames("scene2"))
    assert frames[0].image_path is None and frames[1].image_path is not None
    assert (frames[0].camera.width, frames[0].camera.height) == (1600, 900)
    assert len(frames[0].ground_truth) > 0


def _write(tmp_path, record, name="data_5.npy") -> Path:
    (tmp_path / "scene1" / "data").mkdir(parents=True, exist_ok=True)
    (tmp_path / "scene1" / "rgb").mkdir(exist_ok=True)
    shutil.copy(SAMPLES / "scene1" / "rgb" / "img_18231.png", tmp_path / "scene1" / "rgb" / "img_5.png")
    path = tmp_path / "scene1" / "data" / name
    np.save(path, record, allow_pickle=True)
    return path


def _good_record() -> dict:
    return load_record(SAMPLES / "scene1" / "data" / "data_18231.npy")


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda _r: [1, 2, 3], r"data_5\.npy: expected a pickled dict"),
        (
            lambda r: {k: v for k, v in r.items() if k not in ("pos_3d", "intr_cam")},
            r"data_5\.npy: .*missing key\(s\) pos_3d, intr_cam",
        ),
        (lambda r: {**r, "ego_pos": [0, 0, 0]}, r"data_5\.npy: 'ego_pos' must be a dict"),
        (lambda r: {**r, "2d_skel": [np.zeros((17, 2))]}, r"data_5\.npy: '2d_skel' must have shape \(N, 20, 2\)"),
        (lambda r: {**r, "pos_3d": r["pos_3d"][:-1]}, r"data_5\.npy: .*different numbers of pedestrians"),
        (lambda r: {**r, "cam2world": np.eye(3)}, r"data_5\.npy: 'cam2world' must have shape \(4, 4\)"),
    ],
)
def test_bad_frame_files(tmp_path, mutate, message):
    _write(tmp_path, mutate(_good_record()))
    with pytest.raises(InputError, match=message):
        list(CarlaDataset(tmp_path).frames("scene1"))


def test_unreadable_frame_file(tmp_path):
    _write(tmp_path, {})
    (tmp_path / "scene1" / "data" / "data_5.npy").write_text("not numpy")
    with pytest.raises(InputError, match=r"data_5\.npy: not a readable \.npy"):
        list(CarlaDataset(tmp_path).frames("scene1"))


def test_bad_roots_and_scenes(tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        CarlaDataset(tmp_path / "nope")
    with pytest.raises(InputError, match="no CARLA scenes"):
        CarlaDataset(tmp_path)
    (tmp_path / "scene3" / "data").mkdir(parents=True)
    ds = CarlaDataset(tmp_path)
    with pytest.raises(InputError, match=r"unknown CARLA scene 'scene9'.*valid: scene3"):
        list(ds.frames("scene9"))
    with pytest.raises(InputError, match="no frame files"):
        list(ds.frames("scene3"))


class _RunsCommand:
    """A pickled object that runs a shell command when unpickled (the issue's payload)."""

    def __init__(self, command: str) -> None:
        self.command = command

    def __reduce__(self):
        import os

        return os.system, (self.command,)


def test_pickle_payload_is_refused_and_never_runs(tmp_path, monkeypatch):
    """A data_<n>.npy whose pickle calls os.system: one InputError naming the file, no command run."""
    monkeypatch.chdir(tmp_path)
    path = _write(tmp_path, np.array(_RunsCommand("touch PWNED"), dtype=object))
    with pytest.raises(InputError, match=r"data_5\.npy: .*refusing to load (posix|nt)\.system"):
        list(CarlaDataset(tmp_path).frames("scene1"))
    assert not (tmp_path / "PWNED").exists()
    # the same payload inside a dict, as a recording's frame would carry it
    np.save(path, {**_good_record(), "2d_skel": [_RunsCommand("touch PWNED")]}, allow_pickle=True)
    with pytest.raises(InputError, match=r"data_5\.npy: .*refusing to load"):
        load_record(path)
    assert not (tmp_path / "PWNED").exists()


def test_ragged_arrays_name_the_file(tmp_path):
    record = _good_record()
    _write(tmp_path, {**record, "bbox_2d": [np.zeros(4), np.zeros(3)] + list(record["bbox_2d"])[2:]})
    with pytest.raises(InputError, match=r"data_5\.npy: 'bbox_2d' must have shape \(N, 4\); entry 1 has shape \(3,\)"):
        list(CarlaDataset(tmp_path).frames("scene1"))
