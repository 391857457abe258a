"""A real full disk: ``pedenv run`` into a 2 MB tmpfs, once with ``--parquet --mcap --rerun``
(JPEG overlays) and once with ``--video-out``. One ``error:`` line, no traceback, and every
output readable up to the last finished frame: ``run.json`` agrees with the whole lines of
``environment.jsonl``, the Parquet file opens, the MCAP and Rerun files hold each frame done,
the mp4s hold each frame done.

Mounting needs root (as CI runs); a machine where root cannot mount a tmpfs fails the test."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import cv2
import numpy as np
import pytest
from test_run_safety import frames_in_video, recording

from cli_in_process import pedenv

#: The size of the file system the run fills (the "2 MB" case of issue 32).
DISK = "2m"


@pytest.fixture()
def small_disk(tmp_path):
    """A 2 MB tmpfs at ``tmp_path/disk``, unmounted after the test."""
    if os.geteuid() != 0:
        pytest.skip("mounting a tmpfs needs root (CI runs as root)")
    disk = tmp_path / "disk"
    disk.mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={DISK}", "tmpfs", str(disk)], check=True)
    try:
        yield disk
    finally:  # a file still open keeps the mount busy: detached then, freed when it closes
        if subprocess.run(["umount", str(disk)], check=False).returncode != 0:
            subprocess.run(["umount", "--lazy", str(disk)], check=True)


def _noise(rec: dict, seed: int = 0) -> None:
    """The recording's images replaced by noise (large overlays and video frames: the disk fills fast)."""
    rng = np.random.default_rng(seed)
    for path in sorted(rec["images"].glob("*.png")):
        cv2.imwrite(str(path), rng.integers(0, 256, (360, 640, 3), np.uint8))


def _run(monkeypatch, capsys, rec: dict, out: Path, *flags) -> tuple[int, str]:
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", rec["images"], "--calibration", rec["calibration"],
                          "--ego-poses", rec["ego_poses"], "--output", out, "--pose-backend", "nobody", *flags)
    return code, err


def _frames_done(out: Path) -> int:
    summary = json.loads((out / "run.json").read_text())
    text = (out / "environment.jsonl").read_text()
    assert text == "" or text.endswith("\n")
    assert [json.loads(line)["frame"] for line in text.splitlines()] == list(range(summary["frames_done"]))
    return summary["frames_done"]


def test_a_full_tmpfs_stops_the_run_with_every_output_readable(small_disk, tmp_path, monkeypatch, capsys):
    import pyarrow.parquet as pq
    import rerun.dataframe as rrd
    from mcap.reader import make_reader

    from pedenv.pose.base import POSE_BACKENDS

    monkeypatch.setitem(POSE_BACKENDS, "nobody", "test_run_safety:Nobody")
    rec = recording(tmp_path / "rec", frames=40, size=(640, 360))
    _noise(rec)

    out = small_disk / "a"
    code, err = _run(monkeypatch, capsys, rec, out, "--parquet", "--mcap", small_disk / "a.mcap",
                     "--rerun", small_disk / "a.rrd")
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    assert code == 2 and len(errors) == 1 and "Traceback" not in err, err
    done = _frames_done(out)
    assert 0 < done < 40, err
    assert pq.read_table(out / "environment.parquet").num_rows == 0  # nobody found, the file whole
    with (small_disk / "a.mcap").open("rb") as f:
        reader = make_reader(f)
        assert reader.get_summary() is not None
        assert sum(1 for _ in reader.iter_messages(topics=["/environment"])) == done
    frames = rrd.load_recording(small_disk / "a.rrd").view(index="frame", contents="/**").select().read_all()
    assert sorted(set(frames.column("frame").to_pylist())) == list(range(done))
    assert frames_in_video(out / "birds_eye.mp4") == done

    for path in small_disk.iterdir():  # the second run gets the whole disk
        shutil.rmtree(path) if path.is_dir() else path.unlink()
    out = small_disk / "b"
    code, err = _run(monkeypatch, capsys, rec, out, "--video-out")
    errors = [line for line in err.splitlines() if line.startswith("error:")]
    assert code == 2 and len(errors) == 1 and "Traceback" not in err, err
    done = _frames_done(out)
    assert 0 < done < 40, err
    assert frames_in_video(out / "overlay.mp4") == done == frames_in_video(out / "birds_eye.mp4")
