"""The static-camera scene: a camera 6 m up, 20 deg down over a plaza; apart from the default set."""

import dataclasses

import numpy as np
import pytest

from pedenv.apps.evaluate import run_evaluation
from pedenv.config import Config
from pedenv.datasets.memory import MemoryDataset
from pedenv.errors import InputError
from pedenv.localization import configure
from pedenv.records import Camera, Scene
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.scenarios import ALL_SCENARIOS, STATIC_SCENARIOS
from pedenv.synthetic.storage import read_scene, write_scenes


@pytest.fixture(scope="module")
def plaza() -> Scene:
    return generate_scenes(0, ["static-plaza"])[0]


def remount(scene: Scene, mount: str) -> Scene:
    def cam(c):
        return Camera(c.intrinsics, c.width, c.height, c.cam_to_vehicle, mount)

    return Scene(scene.name, tuple(dataclasses.replace(f, camera=cam(f.camera)) for f in scene.frames))


def test_the_static_scene_is_named_only(plaza):
    assert "static-plaza" in STATIC_SCENARIOS and "static-plaza" not in SCENARIOS
    assert ALL_SCENARIOS == SCENARIOS + STATIC_SCENARIOS
    assert [s.name for s in generate_scenes(0, duration_s=1.0)] == list(SCENARIOS)  # the default set is unchanged
    with pytest.raises(InputError, match="valid: .*static-plaza"):
        generate_scenes(0, ["static-square"])


def test_the_static_camera_stands_6_m_up_looking_20_deg_down(plaza):
    assert len(plaza) == 150
    cam = plaza.frames[0].camera
    assert cam.static
    forward = cam.cam_to_vehicle[:3, 2]
    assert np.degrees(np.arcsin(-forward[2])) == pytest.approx(20.0)
    assert cam.cam_to_vehicle[2, 3] == pytest.approx(6.0)
    for f in plaza.frames:
        np.testing.assert_array_equal(f.ego.matrix, np.eye(4))
    counts = [len(f.ground_truth) for f in plaza.frames]
    assert 30 <= np.mean(counts) <= 50  # a busy plaza
    ranges = np.concatenate([np.linalg.norm(f.ground_truth.positions[:, :2], axis=1) for f in plaza.frames])
    assert ranges.min() < 16.0 and ranges.max() > 55.0  # well beyond the vehicle's 20 m ground limit


def test_storage_keeps_the_mount(plaza, tmp_path):
    write_scenes([plaza], tmp_path)
    back = read_scene(tmp_path / "static-plaza")
    assert all(f.camera.static for f in back.frames)
    vehicle = generate_scenes(0, ["standing-pedestrians"], duration_s=1.0)
    write_scenes(vehicle, tmp_path / "v")
    with np.load(tmp_path / "v" / "standing-pedestrians" / "frames.npz") as data:
        assert "camera_static" not in data.files  # vehicle scenes are stored as before


#: The synthetic camera is known exactly and its skeletons' ankles sit at the anatomical height.
EXACT = {"static_camera_tilt_std_deg": 0.0, "static_camera_height_std_m": 0.0, "ankle_keypoint_offset_m": 0.0,
         "ankle_keypoint_offset_std_m": 0.0}


def _figures(scene, method, backend, fused=None):
    config = configure(Config(), method)
    if fused:
        config = dataclasses.replace(config, fused=dataclasses.replace(config.fused, **fused))
    m = run_evaluation(MemoryDataset([scene]), config=config, pose_backend=backend).metrics
    return m.overall.rel_error_pct, m.calibration["within_1sigma"], m.calibration["within_2sigma"], m.overall.count


@pytest.mark.slow
@pytest.mark.parametrize("backend, exact, static, vehicle", [
    # (rel. error %, 1 sigma, 2 sigma, matched) measured with benchmarks/static_cameras.py --only synthetic:
    # static with the scene's exact camera and ankles, static with the defaults (an estimated camera's
    # tilt and height errors, the real network's ankle offset and its spread), vehicle-mounted
    ("detector-model:yolo11n-pose-far", (0.61, 0.423, 0.836, 3907), (1.05, 0.574, 0.893, 3907),
     (4.10, 0.455, 0.849, 3907)),
    ("ground-truth", (0.37, 0.756, 0.947, 6241), (0.92, 0.812, 0.998, 6241), (3.96, 0.610, 0.964, 6241)),
])
def test_static_scene_figures(plaza, backend, exact, static, vehicle):
    for mount, fused, expected in (("static", EXACT, exact), ("static", None, static), ("vehicle", None, vehicle)):
        rel, one, two, count = _figures(remount(plaza, mount), "fused", backend, fused)
        assert rel == pytest.approx(expected[0], abs=0.05)
        assert (one, two) == pytest.approx(expected[1:3], abs=0.01)
        assert count == expected[3]
