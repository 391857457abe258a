"""Static cameras in the user's recordings: ``mount`` in the calibration, runs without ego poses, ``--static``."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml

from pedenv.datasets.ucmctrack import read_camera_parameters, static_camera
from pedenv.errors import InputError
from pedenv.recordings.footage import load_calibration, load_recording
from pedenv.records import Camera

from cli_in_process import pedenv
from shared_paths import REAL_SAMPLES

MOT17_ROOT = REAL_SAMPLES / "mot17"
CALIB = {"width": 64, "height": 48, "intrinsics": [[50, 0, 32], [0, 50, 24], [0, 0, 1]],
         "cam_to_vehicle": {"rotation": [0.5, -0.5, 0.5, -0.5], "translation": [0.0, 0.0, 6.0]}}


def _calib(tmp_path: Path, **extra) -> Path:
    path = tmp_path / "calib.yaml"
    path.write_text(yaml.safe_dump({**CALIB, **extra}))
    return path


def _images(tmp_path: Path, n: int = 3) -> Path:
    folder = tmp_path / "images"
    folder.mkdir()
    for i in range(n):
        cv2.imwrite(str(folder / f"{i:06d}.png"), np.full((48, 64, 3), 40 * i, np.uint8))
    return folder


@pytest.mark.parametrize("extra, mount", [({}, "vehicle"), ({"mount": "vehicle"}, "vehicle"),
                                          ({"mount": "static"}, "static")])
def test_mount_is_read_from_the_calibration(tmp_path, extra, mount):
    cam = load_calibration(_calib(tmp_path, **extra))
    assert cam.mount == mount and cam.static == (mount == "static")


@pytest.mark.parametrize("value", ["parked", "", 1, None, ["static"]])
def test_a_bad_mount_names_the_file_and_the_field(tmp_path, value):
    path = _calib(tmp_path, mount=value)
    with pytest.raises(InputError, match=r"calib\.yaml: calibration field 'mount' must be one of vehicle, static"):
        load_calibration(path)


def test_camera_refuses_an_unknown_mount():
    with pytest.raises(InputError, match="camera mount must be one of vehicle, static, got 'tripod'"):
        Camera(np.eye(3), 64, 48, mount="tripod")


def test_a_static_recording_needs_no_ego_poses(tmp_path):
    images = _images(tmp_path)
    rec = load_recording(calibration=_calib(tmp_path, mount="static"), ego_poses=None, images=images, fps=10.0)
    frames = list(rec.frames())
    assert [f.timestamp for f in frames] == pytest.approx([0.0, 0.1, 0.2])
    for f in frames:
        assert f.camera.static
        np.testing.assert_array_equal(f.ego.matrix, np.eye(4))  # the vehicle frame stays where it is
    # --static mounts a camera static whatever its calibration says
    forced = load_recording(calibration=_calib(tmp_path), ego_poses=None, images=images, fps=10.0, static=True)
    assert next(forced.frames()).camera.static


def test_a_vehicle_camera_without_ego_poses_is_refused(tmp_path):
    with pytest.raises(InputError, match="a vehicle-mounted camera needs ego poses"):
        load_recording(calibration=_calib(tmp_path), ego_poses=None, images=_images(tmp_path), fps=10.0)


def test_run_without_ego_poses_on_featureless_images_is_one_error_line(monkeypatch, capsys, tmp_path):
    # without --ego-poses a vehicle's poses come from visual odometry, which flat grey images cannot give
    code, out, err = pedenv(monkeypatch, capsys, "run", "--calibration", _calib(tmp_path), "--images",
                            _images(tmp_path), "--fps", "10", "--output", tmp_path / "run")
    assert code == 2
    assert "000000.png: frame 0: too dark, blurred or covered for visual odometry: 0 tracks" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    # the odometry runs in the frame loop: the run stopped at its first frame, and run.json says so
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    assert run["frames_done"] == 0 and run["ego_poses"]["source"] == "estimated" and run["ego_poses"]["file"] is None


def test_mot17_with_ucmctracks_camera_as_a_static_recording(tmp_path):
    from pedenv.recordings.footage_writer import write_mot17_static_recording

    out = write_mot17_static_recording(MOT17_ROOT / "MOT17-04-FRCNN",
                                       MOT17_ROOT / "ucmctrack_cam_para" / "MOT17-04-FRCNN.txt", tmp_path / "rec")
    assert yaml.safe_load((out / "calibration.yaml").read_text())["mount"] == "static"
    assert not (out / "ego_poses.csv").exists()
    rec = load_recording(calibration=out / "calibration.yaml", ego_poses=None, images=out / "images")
    assert len(rec) == 8 and rec.camera.static
    assert rec.camera.cam_to_vehicle[2, 3] == pytest.approx(7.29, abs=0.005)
    assert [t for _, t in rec.images][:2] == pytest.approx([0.0, 1 / 30])


@pytest.mark.slow
def test_run_static_on_a_real_street_camera(monkeypatch, capsys, tmp_path):
    """``pedenv run --static`` on MOT17-09 (4 frames, the real network) with UCMCTrack's camera, no ego poses."""
    seq = MOT17_ROOT / "MOT17-09-FRCNN"
    cam = static_camera(read_camera_parameters(MOT17_ROOT / "ucmctrack_cam_para" / "MOT17-09-FRCNN.txt"), 1920, 1080)
    calib = tmp_path / "calibration.yaml"
    calib.write_text(yaml.safe_dump({
        "width": 1920, "height": 1080, "intrinsics": cam.intrinsics.tolist(),
        "cam_to_vehicle": {"rotation": cam.cam_to_vehicle[:3, :3].tolist(),
                           "translation": cam.cam_to_vehicle[:3, 3].tolist()}}))
    images = tmp_path / "images"
    images.mkdir()
    for p in sorted((seq / "img1").glob("*.jpg")):
        (images / p.name).symlink_to(p.resolve())
    code, out, err = pedenv(monkeypatch, capsys, "run", "--calibration", calib, "--static", "--images", images,
                            "--fps", "30", "--output", tmp_path / "run")
    assert code == 0, err
    lines = [json.loads(line) for line in (tmp_path / "run" / "environment.jsonl").read_text().splitlines()]
    assert len(lines) == 4
    peds = [p for line in lines for p in line["pedestrians"]]
    assert len(peds) >= 16  # 6 people in each frame, most of them found
    assert all(line["ego"]["translation"] == [0.0, 0.0, 0.0] for line in lines)
    ground = [p for p in peds if p["source"].startswith("ground")]
    assert len(ground) >= len(peds) // 2  # the calibrated ground places most of them
