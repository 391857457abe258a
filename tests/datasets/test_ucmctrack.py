"""UCMCTrack's estimated MOT17 cameras, read from the real files, and the static scenes made from them."""

from pathlib import Path

import numpy as np
import pytest

from pedenv.datasets.ucmctrack import (
    ground_points,
    mot17_static_scene,
    read_camera_parameters,
    static_camera,
)
from pedenv.errors import InputError

from shared_paths import REAL_SAMPLES

MOT17 = REAL_SAMPLES / "mot17"
CAM_PARA = MOT17 / "ucmctrack_cam_para"


@pytest.mark.parametrize("seq, height, down, focal", [
    # the samples' README table: centre height, looks down, f
    ("02", 1.73, 4.0, 1300.0), ("04", 7.29, 62.3, 1059.0), ("05", 1.24, 1.9, 663.0), ("09", 1.13, 0.8, 1265.0),
    ("10", 2.05, 12.5, 1054.0), ("11", 1.25, 5.5, 1474.0), ("13", 3.15, 4.9, 843.0),
])
def test_the_seven_cameras(seq, height, down, focal):
    params = read_camera_parameters(CAM_PARA / f"MOT17-{seq}-FRCNN.txt")
    assert params.centre[2] == pytest.approx(height, abs=0.005)
    cam = static_camera(params, 1920, 1080)
    assert cam.static and cam.intrinsics[0, 0] == focal
    assert cam.cam_to_vehicle[2, 3] == pytest.approx(height, abs=0.005)
    forward = cam.cam_to_vehicle[:3, 2]
    assert forward[1] == pytest.approx(0.0, abs=1e-9)  # the vehicle's x is the optical axis seen from above
    assert np.degrees(np.arcsin(-forward[2])) == pytest.approx(down, abs=0.05)
    assert static_camera(params, 1920, 1080, "vehicle").mount == "vehicle"


def test_the_camera_maps_the_world_as_the_file_says():
    params = read_camera_parameters(CAM_PARA / "MOT17-02-FRCNN.txt")
    cam = static_camera(params, 1920, 1080)
    # a world point's pixel through R, T, K equals its ground point's pixel through the camera
    world = np.array([[3.0, 8.0, 0.0], [-2.0, 15.0, 0.0]])
    x_cam = world @ params.rotation.T + params.translation
    pixels = (x_cam @ params.intrinsics.T)[:, :2] / x_cam[:, 2:]
    points, near = ground_points(cam, pixels)
    assert near.all()
    np.testing.assert_allclose(np.linalg.norm(points[:, :2], axis=1),
                               np.linalg.norm(world[:, :2] - params.centre[:2], axis=1), rtol=1e-4)  # R to 5 digits


@pytest.mark.parametrize("seq, frames, people, median_range", [
    ("02", 4, 88, 22.0), ("04", 8, 336, 7.8), ("09", 4, 24, 8.5),
])
def test_mot17_static_scenes(seq, frames, people, median_range):
    scene = mot17_static_scene(MOT17 / f"MOT17-{seq}-FRCNN", CAM_PARA / f"MOT17-{seq}-FRCNN.txt")
    assert len(scene) == frames and all(f.camera.static for f in scene.frames)
    assert sum(len(f.ground_truth) for f in scene.frames) == people  # every box's bottom meets the ground
    ranges = np.concatenate([np.linalg.norm(f.ground_truth.positions[:, :2], axis=1) for f in scene.frames])
    assert np.median(ranges) == pytest.approx(median_range, abs=0.1)
    assert scene.frames[1].timestamp == pytest.approx(1 / 30)
    assert all(f.image_path.is_file() for f in scene.frames)


@pytest.mark.parametrize("text, message", [
    ("", "block RotationMatrices must hold 3 row"),
    ("1 2 3\n", "line 1 holds numbers before a block name"),
    ("RotationMatrices\n1 0 0\n0 1 0\n0 0 x\n", "line 4 must hold numbers"),
    ("RotationMatrices\n1 0 0\n0 1 0\n0 0 -1\nTranslationVectors\n0 0 0\nIntrinsicMatrix\n1 0 0\n0 1 0\n0 0 1\n",
     "not a right-handed rotation"),
    ("RotationMatrices\n1 0 0\n0 1 0\n0 0 1\nTranslationVectors\n0 0\nIntrinsicMatrix\n1 0 0\n0 1 0\n0 0 1\n",
     "block TranslationVectors must hold 1 row"),
])
def test_bad_files_name_the_file_and_the_block(tmp_path: Path, text, message):
    path = tmp_path / "cam.txt"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as err:
        read_camera_parameters(path)
    assert str(path) in str(err.value)
