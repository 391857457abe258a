"""The command line as a user meets it: a subprocess, its output files and its error lines."""

import json
import subprocess
import sys

import pytest


def pedenv(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "pedenv", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=600)


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    root = tmp_path_factory.mktemp("sim")
    done = pedenv("simulate", "--output", root, "--scenes", 2, "--seed", 3)
    assert done.returncode == 0, done.stderr
    assert "wrote 2 scenes" in done.stdout
    return root


@pytest.mark.slow
def test_evaluate_writes_metrics_and_prints_table_one(simulated, tmp_path):
    done = pedenv("evaluate", "--dataset", "synthetic", "--data-root", simulated, "--output", tmp_path,
                  "--pose-backend", "ground-truth", "--ablation")
    assert done.returncode == 0, done.stderr
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert [s["name"] for s in metrics["scenes"]] == ["drive-30kmh-sidewalk", "red-light-crossing"]
    assert 0 < metrics["overall"]["rel_error_pct"] < 30 and metrics["overall"]["count"] > 1000
    assert metrics["info"]["method"] == "fused"  # the default; the ablation is the paper method's
    assert "all keypoints, no refinement" in done.stdout and (tmp_path / "ablation.json").is_file()
    lines = (tmp_path / "environment.jsonl").read_text().splitlines()
    assert len(lines) == 400  # 2 scenes x 200 frames at 10 Hz


@pytest.mark.parametrize(
    "args, message",
    [
        (
            ["evaluate", "--dataset", "waymo", "--data-root", ".", "--output", "o"],
            "unknown dataset 'waymo'; valid: synthetic, nuscenes, carla, kitti",
        ),
        (
            ["evaluate", "--dataset", "synthetic", "--data-root", "SIM", "--output", "o", "--scenes", "nowhere"],
            "unknown scene(s) nowhere in synthetic; scenes there: drive-30kmh-sidewalk, red-light-crossing",
        ),
        (
            ["evaluate", "--dataset", "synthetic", "--data-root", "SIM", "--output", "o", "--pose-backend", "cid"],
            "unknown pose backend 'cid'; valid: ground-truth, detector-model, onnx, ultralytics",
        ),
        (["simulate", "--output", "o", "--format", "kitti"], "unknown scene format 'kitti'"),
        (["demo", "--method", "magic", "--output", "o"], "unknown position method 'magic'; valid: paper, fused"),
        (
            ["evaluate", "--dataset", "synthetic", "--data-root", "SIM", "--output", "o", "--no-refinement"],
            "--no-refinement and --initial-estimate change the paper's method, not fused; add --method paper",
        ),
        (
            ["run", "--images", ".", "--calibration", "c.yaml", "--ego-poses", "p.csv", "--output", "o",
             "--method", "magic"],
            "unknown position method 'magic'; valid: paper, fused",
        ),
    ],
)
def test_bad_input_gives_one_error_line(simulated, tmp_path, args, message):
    args = [str(simulated) if a == "SIM" else a for a in args]
    done = pedenv(*args, cwd=tmp_path)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0]
