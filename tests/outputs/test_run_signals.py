"""``pedenv run`` stopped by SIGTERM part-way, and Ctrl-C again while its outputs close: the
process ends (exit code 130), ``run.json`` is written and agrees with the whole lines of
``environment.jsonl``, and both mp4s are readable to the last frame written.

The run is the real command in a subprocess (its signal handlers are the CLI's); the pose
network is replaced by a backend that finds no one and takes 20 ms a frame (no network, and a
run long enough to be stopped part-way)."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import cv2
from test_run_safety import frames_in_video, recording

HARNESS = """
import os, signal, sys, time
from pedenv.apps.output_safety import RunFolder
from pedenv.pose.base import POSE_BACKENDS
from pedenv.records import Detections

class Slow:
    name = "slow-nobody"
    def __init__(self, **options):
        pass
    def __call__(self, frame, *tracks):
        time.sleep(0.02)
        return Detections.empty()

listing = RunFolder.list_files
def list_files(self, *more):  # the close has begun: Ctrl-C again, handled here
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(0.2)
    return listing(self, *more)

RunFolder.list_files = list_files
POSE_BACKENDS["slow-nobody"] = "__main__:Slow"
from pedenv.cli.app import main
sys.argv = ["pedenv", *sys.argv[1:]]
main()
"""


def test_sigterm_and_ctrl_c_during_the_close_leave_every_output_whole(tmp_path):
    rec = recording(tmp_path / "rec", frames=600)
    (tmp_path / "harness.py").write_text(HARNESS)
    out = tmp_path / "o"
    proc = subprocess.Popen([sys.executable, str(tmp_path / "harness.py"), "run", "--images", rec["images"],
                             "--calibration", rec["calibration"], "--ego-poses", rec["ego_poses"], "--output", out,
                             "--pose-backend", "slow-nobody", "--video-out"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    jsonl = out / "environment.jsonl"
    deadline = time.monotonic() + 120
    while proc.poll() is None and time.monotonic() < deadline:
        if jsonl.is_file() and jsonl.read_text().count("\n") >= 20:
            break
        time.sleep(0.1)
    assert proc.poll() is None, proc.stderr.read() if proc.stderr else ""
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)  # a hang fails here
    assert proc.returncode == 130 and "Traceback" not in err, err
    assert "still closing the outputs; they are kept" in err
    summary = json.loads((out / "run.json").read_text())
    text = jsonl.read_text()
    assert text.endswith("\n") and [json.loads(line)["frame"] for line in text.splitlines()] == \
        list(range(summary["frames_done"]))
    assert 20 <= summary["frames_done"] < 600 == summary["frames_total"]
    assert frames_in_video(out / "overlay.mp4") == summary["frames_done"]
    cap = cv2.VideoCapture(str(out / "birds_eye.mp4"))
    assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == summary["frames_done"]
    cap.release()
