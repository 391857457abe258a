"""``pedenv evaluate`` with --parquet, --rerun and --mcap, as a user runs it."""

import json
import subprocess
import sys

import pyarrow.parquet as pq
import pytest
import rerun.dataframe as rrd
from mcap.reader import make_reader


def pedenv(*args):
    """``pedenv ARGS`` in a subprocess, as a user runs it."""
    return subprocess.run([sys.executable, "-m", "pedenv", *map(str, args)], capture_output=True, text=True,
                          timeout=600)


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    """One simulated scene (seed 4), written once for both tests."""
    folder = tmp_path_factory.mktemp("outputs-cli") / "sim"
    assert pedenv("simulate", "--output", folder, "--scenes", 1, "--seed", 4).returncode == 0
    return folder


@pytest.mark.slow
def test_evaluate_writes_the_tables_the_recording_and_the_mcap(tmp_path, sim):
    out = tmp_path / "out"
    done = pedenv("evaluate", "--dataset", "synthetic", "--data-root", sim, "--output", out,
                  "--pose-backend", "ground-truth", "--parquet", "--rerun", out / "eval.rrd",
                  "--mcap", out / "eval.mcap")
    assert done.returncode == 0, done.stderr
    frames = len((out / "environment.jsonl").read_text().splitlines())
    assert frames == 200
    matches = pq.read_table(out / "matches.parquet")
    count = json.loads((out / "metrics.json").read_text())["overall"]["count"]
    assert matches.num_rows == count > 1000
    assert pq.read_table(out / "environment.parquet").num_rows >= count
    view = rrd.load_recording(out / "eval.rrd").view(index="frame", contents="/**")
    assert view.select().read_all().num_rows == frames
    with (out / "eval.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    assert sum(summary.statistics.channel_message_counts.values()) == 7 * frames  # 7 topics per frame, no image


@pytest.mark.slow
def test_evaluate_both_methods_writes_each_methods_tables_and_recordings(tmp_path, sim):
    out = tmp_path / "out"
    done = pedenv("evaluate", "--dataset", "synthetic", "--data-root", sim, "--output", out,
                  "--pose-backend", "ground-truth", "--method", "both", "--parquet", "--rerun", out / "eval.rrd",
                  "--mcap", out / "eval.mcap")
    assert done.returncode == 0, done.stderr
    assert "paper rel. [%]" in done.stdout and "fused rel. [%]" in done.stdout
    saved = json.loads((out / "metrics.json").read_text())["methods"]
    for method in ("paper", "fused"):
        assert saved[method]["info"]["method"] == method
        folder = out / method
        count = saved[method]["overall"]["count"]
        assert len((folder / "environment.jsonl").read_text().splitlines()) == 200
        assert pq.read_table(folder / "matches.parquet").num_rows == count > 1000
        assert pq.read_table(folder / "environment.parquet").num_rows >= count
        view = rrd.load_recording(out / f"eval-{method}.rrd").view(index="frame", contents="/**")
        assert view.select().read_all().num_rows == 200
        with (out / f"eval-{method}.mcap").open("rb") as f:
            summary = make_reader(f).get_summary()
        assert sum(summary.statistics.channel_message_counts.values()) == 7 * 200
    assert not (out / "eval.rrd").exists() and not (out / "environment.parquet").exists()
