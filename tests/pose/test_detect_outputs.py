"""``pedenv detect`` with bad images and clashing names (issue 10.4, 10.5)."""

from __future__ import annotations

import json
import shutil

import pytest

from cli_in_process import pedenv

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model]



def test_corrupt_image_is_named_and_the_good_ones_are_written(tmp_path, use_pose_cache, photo, monkeypatch, capsys):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    shutil.copy(photo("bus.jpg"), tmp_path / "a" / "img.jpg")
    shutil.copy(photo("zidane.jpg"), tmp_path / "b" / "img.jpg")  # the same file name in another folder
    corrupt = tmp_path / "corrupt.png"
    corrupt.write_bytes(b"\x89PNG\r\n\x1a\n truncated")
    out = tmp_path / "out"
    code, _, err = pedenv(monkeypatch, capsys, "detect", tmp_path / "a" / "img.jpg", tmp_path / "b" / "img.jpg",
                          corrupt, "--output", out, "--pose-input-size", "384x640")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and "1 of 3 images could not be processed" in lines[0]
    assert "corrupt.png: cannot read the image" in lines[0] and "detections.json" in lines[0]
    data = json.loads((out / "detections.json").read_text())
    counts = [len(d["persons"]) for d in data["images"]]
    assert counts[0] >= 3 and counts[1] == 2  # bus.jpg and zidane.jpg, each under its own drawn file
    assert [d["drawn"].rsplit("/", 1)[-1] for d in data["images"]] == ["img_pose.png", "img-2_pose.png"]
    assert (out / "img_pose.png").is_file() and (out / "img-2_pose.png").is_file()
    assert [f["file"] for f in data["failed"]] == [str(corrupt)]


def test_detect_output_that_is_a_file_is_one_error_line(tmp_path, use_pose_cache, photo, monkeypatch, capsys):
    (tmp_path / "taken").write_text("mine")
    code, _, err = pedenv(monkeypatch, capsys, "detect", photo("bus.jpg"), "--output", tmp_path / "taken")
    assert code == 2 and err.strip().splitlines() == [f"error: output folder {tmp_path / 'taken'} is an existing file; "
                                                      f"choose a folder"]


def test_run_output_under_a_file_is_one_error_line(tmp_path, use_pose_cache, monkeypatch, capsys):
    (tmp_path / "images").mkdir()
    import cv2
    import numpy as np

    cv2.imwrite(str(tmp_path / "images" / "f0.png"), np.zeros((48, 64, 3), np.uint8))
    (tmp_path / "calib.yaml").write_text(
        "width: 64\nheight: 48\nintrinsics: [[50, 0, 32], [0, 50, 24], [0, 0, 1]]\n"
        "cam_to_vehicle: {rotation: [0.5, -0.5, 0.5, -0.5], translation: [1, 0, 1.5]}\n"
    )
    (tmp_path / "poses.csv").write_text("timestamp,x,y,yaw\n0,0,0,0\n1,1,0,0\n")
    (tmp_path / "taken").write_text("mine")
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", tmp_path / "images", "--fps", "10",
                          "--calibration", tmp_path / "calib.yaml", "--ego-poses", tmp_path / "poses.csv",
                          "--output", tmp_path / "taken" / "out")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "which is a file" in err
