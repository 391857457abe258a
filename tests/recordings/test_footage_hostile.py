"""Issue 10.6/10.8 for the user's recordings: wrong input is refused or warned about, naming the file."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import cv2
import numpy as np
import pytest
from test_footage import _bus_recording, _calib, _write, pose_env  # noqa: F401 - pose_env is a fixture

from pedenv.errors import InputError
from pedenv.recordings.footage import MAX_PLAUSIBLE_EGO_SPEED_MPS, load_calibration, load_ego_poses, load_recording


def test_intrinsics_last_row_must_be_0_0_1(tmp_path):
    path = _calib(tmp_path, intrinsics=[[50, 0, 32], [0, 50, 24], [0, 0, 5]])
    with pytest.raises(InputError, match=r"calib\.yaml: calibration field 'intrinsics' must have the last row "
                                         r"\[0, 0, 1\], got \[0\.0, 0\.0, 5\.0\]"):
        load_calibration(path)


def test_binary_calibration_and_poses_name_the_file(tmp_path):
    (tmp_path / "calib.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff\xfe\xfd")
    with pytest.raises(InputError, match=r"calib\.yaml: the calibration is not UTF-8 text"):
        load_calibration(tmp_path / "calib.yaml")
    (tmp_path / "poses.csv").write_bytes(b"\xff\xfe\x00timestamp\x00\x81")
    with pytest.raises(InputError, match=r"poses\.csv: the ego poses are not a UTF-8 CSV"):
        load_ego_poses(tmp_path / "poses.csv")


def test_byte_order_mark_in_poses_header_is_accepted(tmp_path):
    path = tmp_path / "poses.csv"
    path.write_bytes("\ufefftimestamp,x,y,yaw\n0,0,0,0\n1,5,0,0\n".encode("utf-8"))
    trajectory = load_ego_poses(path)
    assert trajectory.translations[:, 0].tolist() == [0.0, 5.0]


def test_ego_pose_jump_is_warned_about(tmp_path):
    text = "timestamp,x,y,yaw\n0,0,0,0\n0.1,1,0,0\n0.2,1001,0,0\n0.3,1002,0,0\n"
    with pytest.warns(UserWarning, match=r"poses\.csv: the ego moves at 10000 m/s between rows 2 and 3 .*"
                                         rf"above the plausible {MAX_PLAUSIBLE_EGO_SPEED_MPS:g} m/s"):
        load_ego_poses(_write(tmp_path / "poses.csv", text))


@pytest.mark.parametrize("fps", [float("inf"), float("nan"), 0.0, -3.0])
def test_fps_must_be_finite_and_positive(tmp_path, fps):
    with pytest.raises(InputError, match=r"fps must be a finite number > 0"):
        load_recording(
            calibration=_calib(tmp_path),
            ego_poses=_write(tmp_path / "p.csv", "timestamp,x,y,yaw\n0,0,0,0\n"),
            images=tmp_path,
            fps=fps,
        )


def _cut_video(path, frames: int = 12):
    """An MJPG video of ``frames`` 640x480 frames, then cut to the first half of its bytes."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (640, 480))
    rng = np.random.default_rng(0)
    for _ in range(frames):
        writer.write(rng.integers(0, 255, (480, 640, 3), np.uint8))
    writer.release()
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return path


@pytest.mark.ultralytics
@pytest.mark.onnx_model
@pytest.mark.slow
def test_video_cut_in_half_is_warned_and_recorded(tmp_path, pose_env, monkeypatch):  # noqa: F811
    from pedenv.apps.run import run_recording

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"])
    video = _cut_video(tmp_path / "cut.avi")
    with pytest.warns(UserWarning, match=r"cut\.avi: the video ended after \d+ of the 12 frames"):
        summary = run_recording(video=video, calibration=rec["calibration"], ego_poses=rec["ego_poses"],
                                output=tmp_path / "out", start_time=49.9)
    saved = json.loads((tmp_path / "out" / "run.json").read_text())
    assert 0 < saved["frames_done"] < 12 and saved["frames_total"] == 12 and "ended after" in saved["ended_early"]
    assert summary == saved


@pytest.mark.ultralytics
@pytest.mark.onnx_model
@pytest.mark.slow
def test_rerun_never_mixes_or_loses_runs(tmp_path, pose_env):  # noqa: F811
    """The issue's re-run: a failing second run truncated the first run's environment.jsonl, and a
    shorter successful re-run left the longer run's overlays behind."""
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"])
    env = {**os.environ, "PEDENV_CACHE": pose_env["PEDENV_CACHE"], "COLUMNS": "1000"}

    def run(*extra, calibration=rec["calibration"], images=rec["images"]):
        args = ["run", "--images", images, "--calibration", calibration, "--ego-poses", rec["ego_poses"],
                "--output", tmp_path / "out", *extra]
        return subprocess.run([sys.executable, "-c", "from pedenv.cli import main; main()", *map(str, args)],
                              capture_output=True, text=True, env=env)

    assert run().returncode == 0
    good = (tmp_path / "out" / "environment.jsonl").read_text()
    assert len(good.splitlines()) == 6
    wrong = _write(tmp_path / "wrong.yaml", rec["calibration"].read_text().replace("width: 640", "width: 600"))
    again = run(calibration=wrong)  # fails at frame 0 (image size); the folder holds the good run
    errors = [line for line in again.stderr.splitlines() if line.startswith("error:")]
    assert again.returncode == 2 and len(errors) == 1 and "is not empty; pass --overwrite" in errors[0]
    assert (tmp_path / "out" / "environment.jsonl").read_text() == good
    shorter = tmp_path / "rec" / "shorter"
    shorter.mkdir()
    for name in ("frame_000.jpg", "frame_001.jpg", "frame_002.jpg"):
        (shorter / name).write_bytes((rec["images"] / name).read_bytes())
    _write(
        shorter / "timestamps.csv", "filename,timestamp\nframe_000.jpg,50.0\nframe_001.jpg,50.1\nframe_002.jpg,50.2\n"
    )
    assert run("--overwrite", images=shorter).returncode == 0
    assert sorted(p.name for p in (tmp_path / "out" / "overlays").iterdir()) == [f"{i:06d}.png" for i in range(3)]
    assert json.loads((tmp_path / "out" / "run.json").read_text())["frames_done"] == 3
