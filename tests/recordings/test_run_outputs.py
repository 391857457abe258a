"""``pedenv run`` on real images with every per-frame output: Parquet, Rerun (with the camera image), MCAP, video."""

import json
import subprocess
import sys

import cv2
import pyarrow.parquet as pq
import pytest
import rerun.dataframe as rrd
from test_footage import _bus_recording, pose_env  # noqa: F401 - the fixture is used by name

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model, pytest.mark.slow]


def test_run_writes_every_output_of_the_bus_recording(tmp_path, pose_env, monkeypatch):  # noqa: F811
    from pedenv.apps.run import run_recording
    from pedenv.outputs.sinks import ExtraOutputs

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    out = tmp_path / "out"
    extra = ExtraOutputs(parquet=out / "environment.parquet", rerun=out / "run.rrd", mcap=out / "run.mcap")
    summary = run_recording(**_bus_recording(tmp_path / "rec", pose_env["bus"]), output=out, extra_outputs=extra)
    lines = [json.loads(line) for line in (out / "environment.jsonl").read_text().splitlines()]
    assert summary["frames_done"] == len(lines) == 6
    assert sorted(summary["files"]) == sorted(str(out / n) for n in ("environment.parquet", "run.rrd", "run.mcap",
                                                                      "birds_eye.mp4"))
    assert pq.read_table(out / "environment.parquet").num_rows == sum(len(line["pedestrians"]) for line in lines) >= 18
    table = rrd.load_recording(out / "run.rrd").view(index="frame", contents="/**").select().read_all()
    assert table.num_rows == 6
    blobs = table.column("/world/ego/camera/image:Blob").to_pylist()
    assert all(b is not None and bytes(b[0][:2]) == b"\xff\xd8" for b in blobs)  # the JPEG files themselves
    assert cv2.VideoCapture(str(out / "birds_eye.mp4")).get(cv2.CAP_PROP_FRAME_COUNT) == 6


def test_run_cli_refuses_a_missing_extra_before_running(tmp_path, pose_env):  # noqa: F811
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"], frames=2)
    code = "import sys; sys.modules['rerun'] = None; from pedenv.cli import main; sys.argv[0] = 'pedenv'; main()"
    args = ["run", "--images", rec["images"], "--calibration", rec["calibration"], "--ego-poses", rec["ego_poses"],
            "--output", tmp_path / "out", "--rerun", tmp_path / "out" / "x.rrd"]
    done = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    errors = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert errors == ['error: --rerun needs the viz extra: pip install -e ".[viz]"'] and "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()
