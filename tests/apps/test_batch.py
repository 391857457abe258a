"""``run_manifest``: recordings of real KITTI frames as tasks; a bad recording is named, the others written."""

import json
import os

import pytest

from pedenv.apps.batch import run_manifest
from pedenv.apps.options import ExecutorOptions, PoseOptions

from cli_in_process import pedenv
from shared_paths import REAL_SAMPLES

pytestmark = pytest.mark.onnx_model

KITTI = REAL_SAMPLES / "kitti" / "tracking_mini" / "training" / "image_02"
CALIBRATION = """width: 1224
height: 370
intrinsics: [[707.05, 0, 604.08], [0, 707.05, 180.51], [0, 0, 1]]
cam_to_vehicle:
  rotation: [0.5, -0.5, 0.5, -0.5]
  translation: [0.0, 0.0, 1.65]
"""


def _link_frames(folder, sequence):
    """The sequence's 3 real frames, linked (read in place, never copied) into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.iterdir():
        old.unlink()
    for i, image in enumerate(sorted((KITTI / sequence).glob("*.png"))):
        os.symlink(image, folder / f"{i:06d}.png")


def _manifest(root):
    """Two recordings of KITTI 0016 (1224x370); the second holds 0001's frames, 1242x375: bad data."""
    root.mkdir()
    (root / "calib.yaml").write_text(CALIBRATION)
    (root / "poses.csv").write_text("timestamp,x,y,yaw\n0,0,0,0\n10,0,0,0\n")
    _link_frames(root / "good" / "images", "0016")
    _link_frames(root / "bad" / "images", "0001")
    manifest = root / "manifest.yaml"
    manifest.write_text("- {name: good, images: good/images, calibration: calib.yaml, ego_poses: poses.csv, fps: 2}\n"
                        "- {name: bad, images: bad/images, calibration: calib.yaml, ego_poses: poses.csv, fps: 2}\n")
    return manifest


@pytest.mark.parametrize("executor", ["serial", pytest.param("ray", marks=pytest.mark.ray)])
def test_a_bad_recording_is_named_the_other_written_and_resume_runs_only_it(request, executor, tmp_path):
    if executor == "ray":
        request.getfixturevalue("ray_session")
    manifest, out = _manifest(tmp_path / "in"), tmp_path / "out"
    summary = run_manifest(manifest, out, PoseOptions(detection="fast"), executor=ExecutorOptions(executor))
    good, bad = summary["recordings"]
    assert summary["failed"] == 1 and json.loads((out / "summary.json").read_text()) == summary
    assert (good["name"], good["status"], good["frames_done"], good["frames_total"]) == ("good", "done", 3, 3)
    assert len((out / "good" / "environment.jsonl").read_text().splitlines()) == 3
    assert sorted(p.name for p in (out / "good" / "overlays").iterdir()) == ["000000.jpg", "000001.jpg", "000002.jpg"]
    assert (bad["name"], bad["status"], bad["row"]) == ("bad", "failed", 2)
    assert "is 1242x375 pixels, the calibration says 1224x370" in bad["error"]
    # the data fixed, --resume keeps the good recording and runs the bad one
    _link_frames(tmp_path / "in" / "bad" / "images", "0016")
    before = (out / "good" / "environment.jsonl").stat().st_mtime_ns
    again = run_manifest(manifest, out, PoseOptions(detection="fast"),
                         executor=ExecutorOptions(executor, resume=True))
    assert [(r["name"], r["status"]) for r in again["recordings"]] == [("good", "resumed"), ("bad", "done")]
    assert again["failed"] == 0 and (out / "good" / "environment.jsonl").stat().st_mtime_ns == before
    assert (out / "bad" / "environment.jsonl").read_text() == (out / "good" / "environment.jsonl").read_text()


def test_run_cli_with_a_manifest_lists_each_recording_and_exits_1_when_one_failed(monkeypatch, capsys, tmp_path):
    manifest = _manifest(tmp_path / "in")
    code, out, err = pedenv(monkeypatch, capsys, "run", "--manifest", manifest, "--output", tmp_path / "out",
                            "--detection", "fast")
    assert code == 1
    assert out.splitlines() == [f"good: done, 3 of 3 frames -> {tmp_path / 'out' / 'good'}",
                                "bad: failed, 0 of 3 frames", f"summary: {tmp_path / 'out' / 'summary.json'}"]
    assert "error: recording bad (row 2) failed: InputError: " in err and "the calibration says 1224x370" in err


@pytest.mark.parametrize("flags, message", [
    (["--images", "x"], "--images: with --manifest each row names its recording's files and timing"),
    (["--parquet"], "--parquet, --rerun and --mcap are written by single-recording runs"),
])
def test_run_cli_refuses_single_recording_flags_beside_a_manifest(monkeypatch, capsys, tmp_path, flags, message):
    manifest = _manifest(tmp_path / "in")
    code, _, err = pedenv(monkeypatch, capsys, "run", "--manifest", manifest, "--output", tmp_path / "out", *flags)
    assert code == 2 and err.startswith(f"error: {message}") and not (tmp_path / "out").exists()
