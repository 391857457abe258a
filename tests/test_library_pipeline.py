"""``pedenv.Pipeline``: the library's per-frame pipeline is what ``pedenv run`` runs, on a real recording."""

import json

import pytest

from pedenv import Config, Pipeline, load_recording
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.recordings.footage_writer import write_kitti_recording

from cli_in_process import pedenv
from shared_paths import REAL_SAMPLES


@pytest.mark.onnx_model
@pytest.mark.ultralytics
def test_the_library_pipeline_and_pedenv_run_write_the_same_environment(tmp_path, monkeypatch, capsys,
                                                                          use_pose_cache):
    """KITTI tracking 0016 of the real samples (3 frames, 0.5 s apart, 8 pedestrians), the network's
    real skeletons: ``Pipeline(Config()).step`` and ``pedenv run`` (both ``stream``, the fused method)
    write byte-identical ``environment.jsonl``."""
    rec = write_kitti_recording(REAL_SAMPLES / "kitti" / "tracking_mini" / "training", "0016", tmp_path / "rec")
    files = {"calibration": rec / "calibration.yaml", "ego_poses": rec / "ego_poses.csv", "images": rec / "images"}
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", files["images"], "--calibration",
                          files["calibration"], "--ego-poses", files["ego_poses"], "--output", tmp_path / "out",
                          "--video-out")
    assert code == 0, err

    pipeline = Pipeline(Config())
    with EnvironmentWriter(tmp_path / "library.jsonl") as writer:
        for frame in load_recording(**files).frames():
            writer.write(pipeline.step(frame))

    ran = (tmp_path / "out" / "environment.jsonl").read_bytes()
    assert (tmp_path / "library.jsonl").read_bytes() == ran
    lines = [json.loads(line) for line in ran.decode().splitlines()]
    assert len(lines) == 3 and max(len(line["pedestrians"]) for line in lines) >= 5
    assert Config.load(tmp_path / "out" / "config.json") == pipeline.config  # stream, as saved by the run
    assert pipeline.config.detection.mode == "stream" and pipeline.frames == 3
