"""Issue 10.6/10.8 for the user's recordings: wrong input is refused or warned about, naming the file."""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

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
    from pedenv.apps.options import RecordingSource
    from pedenv.apps.run import run_recording

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"])
    video = _cut_video(tmp_path / "cut.avi")
    with pytest.warns(UserWarning, match=r"cut\.avi: the video ended after \d+ of the 12 frames"):
        source = RecordingSource(video=video, calibration=rec["calibration"], ego_poses=rec["ego_poses"],
                                 start_time=49.9)
        summary = run_recording(source, tmp_path / "out")
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
    again = run(calibration=wrong)  # fails at frame 0 (image size), checked first; the folder holds the good run
    errors = [line for line in again.stderr.splitlines() if line.startswith("error:")]
    assert again.returncode == 2 and len(errors) == 1 and "frame 0 is 640x480 pixels, the calibration says 600x480" \
        in errors[0]
    again = run("--overwrite", calibration=wrong)  # issue 19: --overwrite no longer empties the folder first
    assert again.returncode == 2 and "frame 0 is 640x480 pixels" in again.stderr
    assert (tmp_path / "out" / "environment.jsonl").read_text() == good
    shorter = tmp_path / "rec" / "shorter"
    shorter.mkdir()
    for name in ("frame_000.jpg", "frame_001.jpg", "frame_002.jpg"):
        (shorter / name).write_bytes((rec["images"] / name).read_bytes())
    _write(
        shorter / "timestamps.csv", "filename,timestamp\nframe_000.jpg,50.0\nframe_001.jpg,50.1\nframe_002.jpg,50.2\n"
    )
    assert run("--overwrite", images=shorter).returncode == 0
    assert sorted(p.name for p in (tmp_path / "out" / "overlays").iterdir()) == [f"{i:06d}.jpg" for i in range(3)]
    assert json.loads((tmp_path / "out" / "run.json").read_text())["frames_done"] == 3


# issue 19 ---------------------------------------------------------------------------------------


def test_ego_positions_beyond_ten_thousand_km_are_refused(tmp_path):
    text = "timestamp,x,y,yaw\n0,0,0,0\n0.1,1e20,0,0\n"
    with pytest.raises(InputError, match=r"poses\.csv: row 2 \(line 3\): x = 1e\+20 m is beyond 1e\+07 m from the "
                                         r"world origin"):
        load_ego_poses(_write(tmp_path / "poses.csv", text))
    utm = load_ego_poses(_write(tmp_path / "utm.csv", "timestamp,x,y,yaw\n0,500000,5400000,0\n0.1,500001,5400000,0\n"))
    assert utm.translations[1, 0] == 500001.0  # UTM coordinates are fine


@pytest.mark.ultralytics  # bus.jpg
def test_every_frame_is_checked_before_an_earlier_run_is_replaced(tmp_path):
    """A bad image anywhere in the folder stops ``run --overwrite`` before it empties the folder."""
    from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource
    from pedenv.apps.run import run_recording

    rec = _bus_recording(tmp_path / "rec", BUS, frames=3)
    out = tmp_path / "out"
    out.mkdir()
    (out / ".pedenv-output").write_text("an earlier run")
    (out / "environment.jsonl").write_text("the earlier run's lines\n")
    (rec["images"] / "frame_002.jpg").write_bytes(b"not a jpeg")
    with pytest.raises(InputError, match=r"frame_002\.jpg: cannot read the image \(corrupt or not an image\)"):
        run_recording(RecordingSource(**rec), OutputOptions(out, overwrite=True), PoseOptions("detector-model"))
    assert (out / "environment.jsonl").read_text() == "the earlier run's lines\n"


BUS = Path(importlib.util.find_spec("ultralytics").submodule_search_locations[0]) / "assets" / "bus.jpg" \
    if importlib.util.find_spec("ultralytics") else None


def _long_bus_recording(folder: Path, photo: Path, frames: int) -> dict:
    """The bus recording with ``frames`` frames and ego poses covering them all (0.7 m/s ahead)."""
    rec = _bus_recording(folder, photo, frames=frames)
    end = 50.0 + 0.1 * frames
    rows = f"49.9,-0.07,0,0,1,0,0,0\n{end:.1f},{0.7 * (end - 50):.3f},0,0,1,0,0,0\n"
    _write(rec["ego_poses"], "timestamp,x,y,z,qw,qx,qy,qz\n" + rows)
    return rec


def _run_cli(args, env) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "pedenv", *map(str, args)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)


def _wait_for(path_glob, folder, proc, timeout: float = 300.0) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline and proc.poll() is None and not list(folder.glob(path_glob)):
        time.sleep(0.05)
    assert proc.poll() is None, f"the run ended before the signal: {proc.stderr.read() if proc.stderr else ''}"


@pytest.mark.ultralytics
@pytest.mark.onnx_model
@pytest.mark.slow
@pytest.mark.parametrize("gap_s", [0.15, 0.3])
def test_a_double_ctrl_c_keeps_run_json(tmp_path, pose_env, gap_s):  # noqa: F811
    rec = _long_bus_recording(tmp_path / "rec", pose_env["bus"], frames=30)
    env = {**os.environ, "PEDENV_CACHE": pose_env["PEDENV_CACHE"]}
    out = tmp_path / "out"
    proc = _run_cli(["run", "--images", rec["images"], "--calibration", rec["calibration"], "--ego-poses",
                     rec["ego_poses"], "--output", out, "--detection", "fast"], env)
    _wait_for("overlays/000002.jpg", out, proc)
    proc.send_signal(signal.SIGINT)
    time.sleep(gap_s)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in err, err
    summary = json.loads((out / "run.json").read_text())
    lines = (out / "environment.jsonl").read_text().splitlines()
    assert 3 <= summary["frames_done"] == len(lines) < 30


@pytest.mark.ultralytics
@pytest.mark.onnx_model
@pytest.mark.slow
def test_a_ctrl_c_manifest_run_writes_summary_json(tmp_path, pose_env):  # noqa: F811
    rec = _long_bus_recording(tmp_path / "rec", pose_env["bus"], frames=12)
    rows = "".join(f"drive-{k},{rec['images']},{rec['calibration']},{rec['ego_poses']}\n" for k in range(6))
    manifest = _write(tmp_path / "drives.csv", "name,images,calibration,ego_poses\n" + rows)
    out = tmp_path / "out"
    proc = _run_cli(["run", "--manifest", manifest, "--output", out, "--detection", "fast"],
                    {**os.environ, "PEDENV_CACHE": pose_env["PEDENV_CACHE"]})
    _wait_for("drive-1/overlays/000001.jpg", out, proc)  # the first recording done, the second running
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in err, err
    summary = json.loads((out / "summary.json").read_text())
    statuses = [r["status"] for r in summary["recordings"]]
    assert summary["interrupted"] is True and statuses[0] == "done" and statuses[-1] == "interrupted"
    assert [r["name"] for r in summary["recordings"]] == [f"drive-{k}" for k in range(6)]


@pytest.mark.ultralytics
@pytest.mark.onnx_model
@pytest.mark.slow
def test_detect_goes_past_a_bad_image_and_takes_any_file_name(tmp_path, pose_env):  # noqa: F811
    """``detect good.jpg 1x1.png good2.jpg``: one error naming the bad file, the two others written;
    names with the byte 0xff (a segfault in cv2.imwrite before) for an image and the output folder."""
    odd = tmp_path / os.fsdecode(b"x\xff.jpg")
    odd.write_bytes(pose_env["bus"].read_bytes())
    tiny = tmp_path / "one.png"
    tiny.write_bytes(cv2.imencode(".png", np.zeros((1, 1, 3), np.uint8))[1].tobytes())
    out = tmp_path / os.fsdecode(b"o\xff")
    done = subprocess.run([sys.executable, "-m", "pedenv", "detect", str(pose_env["bus"]), str(tiny), str(odd),
                           "--output", str(out), "--detection", "fast"], capture_output=True, text=True,
                          env={**os.environ, "PEDENV_CACHE": pose_env["PEDENV_CACHE"]}, timeout=300)
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == 2 and len(errors) == 1 and "Traceback" not in done.stderr, done.stderr
    assert f"1 of 3 images could not be processed ({tiny}: image of 1x1 px is too small" in errors[0]
    data = json.loads((out / "detections.json").read_text())
    assert [os.fsencode(Path(d["file"]).name) for d in data["images"]] == [b"bus.jpg", b"x\xff.jpg"]
    assert data["failed"][0]["file"] == str(tiny) and all(len(d["persons"]) >= 3 for d in data["images"])
    assert sorted(os.fsencode(p.name) for p in out.glob("*_pose.png")) == [b"bus_pose.png", b"x\xff_pose.png"]
