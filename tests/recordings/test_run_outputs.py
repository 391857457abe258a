"""``pedenv run`` on real images with every per-frame output: Parquet, Rerun (with the camera image), MCAP, video."""

import json
import os
import signal
import subprocess
import sys
import time

import cv2
import numpy as np
import pyarrow.parquet as pq
import pytest
import rerun.dataframe as rrd
from test_footage import _bus_recording, pose_env  # noqa: F401 - the fixture is used by name

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model, pytest.mark.slow]


def test_run_writes_every_output_of_the_bus_recording(tmp_path, pose_env, monkeypatch):  # noqa: F811
    from pedenv.apps.options import OutputOptions, RecordingSource
    from pedenv.apps.run import run_recording
    from pedenv.outputs.sinks import ExtraOutputs

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    out = tmp_path / "out"
    extra = ExtraOutputs(parquet=out / "environment.parquet", rerun=out / "run.rrd", mcap=out / "run.mcap")
    summary = run_recording(RecordingSource(**_bus_recording(tmp_path / "rec", pose_env["bus"])),
                            OutputOptions(out, extra=extra, overlays="png"))
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
    # written beside the network by the pipeline, in frame order
    assert [line["frame"] for line in lines] == list(range(6))
    assert sorted(p.name for p in (out / "overlays").iterdir()) == [f"{i:06d}.png" for i in range(6)]
    overlay = cv2.imread(str(out / "overlays" / "000005.png"))  # stored: the pixels' bytes plus 0.1 % at most
    assert overlay.nbytes < (out / "overlays" / "000005.png").stat().st_size < 1.001 * overlay.nbytes
    run = json.loads((out / "run.json").read_text())
    assert run["speed"]["pipeline"]["nice"] == 10  # the light outputs' writer runs after the network
    assert run["pose_backend"]["device"] == "auto" and run["pose_backend"]["provider"] == "CPUExecutionProvider"
    speed = run["speed"]
    assert speed["frames_dropped"] == run["frames_dropped"] == 0 and speed["frames_per_second"] > 0
    assert speed["latency_ms"]["p95"] >= speed["latency_ms"]["median"] >= speed["network_ms_per_frame"] > 0
    assert speed["network_passes_per_frame"] >= 1.0


def test_run_video_out_and_deflated_pngs_hold_the_same_overlays(tmp_path, pose_env, monkeypatch):  # noqa: F811
    """``--video-out``: overlay.mp4 has every frame in RGB order turned to the video's BGR (an overlay
    differs from its camera image only where it is drawn on); ``--png-compression fast``: the
    same overlays as the stored default, deflated, and the writer not made nicer than the network."""
    from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource
    from pedenv.apps.run import run_recording

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    rec = RecordingSource(**_bus_recording(tmp_path / "rec", pose_env["bus"], frames=3))
    pose = PoseOptions(detection="fast")
    runs = {name: run_recording(rec, OutputOptions(tmp_path / name, **options), pose)
            for name, options in (("mp4", {"video_out": True}), ("stored", {"overlays": "png"}),
                                  ("fast", {"overlays": "png", "png_compression": "fast"}))}
    assert [runs[n]["speed"]["pipeline"]["nice"] for n in ("mp4", "stored", "fast")] == [10, 10, 0]
    cap = cv2.VideoCapture(str(tmp_path / "mp4" / "overlay.mp4"))
    assert cap.get(cv2.CAP_PROP_FRAME_COUNT) == 3
    ok, first = cap.read()
    camera = cv2.imread(str(rec.images / "frame_000.jpg")).astype(float)
    assert ok and np.median(np.abs(first - camera)) < 6 < np.median(np.abs(first[..., ::-1] - camera))
    for i in range(3):
        stored, fast = (tmp_path / n / "overlays" / f"{i:06d}.png" for n in ("stored", "fast"))
        np.testing.assert_array_equal(cv2.imread(str(stored)), cv2.imread(str(fast)))
        assert fast.stat().st_size < 0.75 * stored.stat().st_size  # 0.70 on these resized JPEG crops


def test_run_realtime_drops_the_frames_that_arrive_while_the_model_is_busy(tmp_path, pose_env, monkeypatch):  # noqa: F811
    """Frames 1 ms apart arrive while the network works on the one before (a pass takes far
    longer); after a 4 s gap the model is free again. So frames 0 and 3 run, 1, 2 and 4 are dropped."""
    from pedenv.apps.options import PoseOptions, RecordingSource
    from pedenv.apps.pipeline import PipelineConfig
    from pedenv.apps.run import run_recording

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"], frames=5)
    stamps = [50.0, 50.001, 50.002, 54.0, 54.001]
    (rec["images"] / "timestamps.csv").write_text(
        "filename,timestamp\n" + "".join(f"frame_{i:03d}.jpg,{t}\n" for i, t in enumerate(stamps)))
    (tmp_path / "poses.csv").write_text("timestamp,x,y,yaw\n49,0,0,0\n55,0,0,0\n")
    out = tmp_path / "out"
    summary = run_recording(RecordingSource(**{**rec, "ego_poses": tmp_path / "poses.csv"}), out,
                            PoseOptions(detection="fast"), pipeline=PipelineConfig(realtime=True))
    assert (summary["frames_done"], summary["frames_dropped"], summary["frames_total"]) == (2, 3, 5)
    lines = [json.loads(line) for line in (out / "environment.jsonl").read_text().splitlines()]
    assert [line["frame"] for line in lines] == [0, 3]
    assert sorted(p.name for p in (out / "overlays").iterdir()) == ["000000.jpg", "000003.jpg"]
    assert json.loads((out / "run.json").read_text())["speed"]["pipeline"]["realtime"] is True


def test_run_cli_refuses_realtime_without_frame_times_and_cuda_without_a_gpu(tmp_path, pose_env, monkeypatch,  # noqa: F811
                                                                           capsys):
    import onnxruntime as ort

    from cli_in_process import pedenv

    monkeypatch.setenv("PEDENV_CACHE", pose_env["PEDENV_CACHE"])
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"], frames=2)
    (rec["images"] / "timestamps.csv").unlink()
    base = ["run", "--images", rec["images"], "--calibration", rec["calibration"], "--ego-poses", rec["ego_poses"]]
    code, _, err = pedenv(monkeypatch, capsys, *base, "--output", tmp_path / "a", "--realtime")
    assert code == 2 and "Traceback" not in err
    assert [line for line in err.splitlines() if line.startswith("error:")] == [
        f"error: {rec['images']}: --realtime takes the frames at their own times, and the folder has no "
        "timestamps.csv (filename,timestamp); add one or give --fps"]
    if "CUDAExecutionProvider" not in ort.get_available_providers():
        code, _, err = pedenv(monkeypatch, capsys, *base, "--fps", "10", "--output", tmp_path / "b", "--device", "cuda")
        errors = [line for line in err.splitlines() if line.startswith("error:")]
        assert code == 2 and "Traceback" not in err and len(errors) == 1
        assert errors[0].startswith("error: --device cuda: this onnxruntime has no CUDA provider")
        assert not (tmp_path / "b").exists()


def test_ctrl_c_leaves_every_finished_frame_of_a_pipelined_run_on_disk(tmp_path, pose_env):  # noqa: F811
    rec = _bus_recording(tmp_path / "rec", pose_env["bus"], frames=40)
    env = {**os.environ, "PEDENV_CACHE": pose_env["PEDENV_CACHE"], "COLUMNS": "1000"}
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-c", "from pedenv.cli import main; main()", "run", "--images",
                             str(rec["images"]), "--calibration", str(rec["calibration"]), "--ego-poses",
                             str(rec["ego_poses"]), "--output", str(out), "--detection", "fast"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env)
    jsonl = out / "environment.jsonl"
    deadline = time.time() + 240
    while time.time() < deadline and proc.poll() is None:
        if jsonl.is_file() and len(jsonl.read_text().splitlines()) >= 4:
            break
        time.sleep(0.1)
    assert proc.poll() is None, proc.stderr.read()
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in err
    lines = [json.loads(line) for line in jsonl.read_text().splitlines()]
    done = len(lines)
    assert 4 <= done < 40 and [line["frame"] for line in lines] == list(range(done))
    assert json.loads((out / "run.json").read_text())["frames_done"] == done
    overlays = sorted((out / "overlays").iterdir())
    assert [p.name for p in overlays] == [f"{i:06d}.jpg" for i in range(done)]
    assert all(cv2.imread(str(p)) is not None for p in overlays)
    assert cv2.VideoCapture(str(out / "birds_eye.mp4")).get(cv2.CAP_PROP_FRAME_COUNT) == done


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
