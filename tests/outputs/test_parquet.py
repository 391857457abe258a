"""environment.parquet and matches.parquet read back with pyarrow, against the JSON Lines and the metrics."""

import json

import numpy as np
import pyarrow.parquet as pq
import pytest
from sink_runs import FRAMES, FailingModel

from pedenv.outputs.parquet import ENVIRONMENT_SCHEMA, MATCHES_SCHEMA, EnvironmentTableWriter


def test_environment_table_has_one_row_per_pedestrian_and_frame(evaluated):
    folder, _, _ = evaluated
    table = pq.read_table(folder / "environment.parquet")
    assert table.schema.equals(ENVIRONMENT_SCHEMA)
    lines = [json.loads(line) for line in (folder / "environment.jsonl").read_text().splitlines()]
    assert len(lines) == 2 * FRAMES
    assert table.num_rows == sum(len(line["pedestrians"]) for line in lines) > 200
    rows = table.to_pylist()
    last = lines[-1]
    mine = [r for r in rows if r["scene"] == last["scene"] and r["frame"] == last["frame"]]
    assert [r["track_id"] for r in mine] == [p["track_id"] for p in last["pedestrians"]]
    for row, ped in zip(mine, last["pedestrians"]):
        assert [row["x"], row["y"], row["z"]] == pytest.approx(ped["position"], abs=1e-3)
        assert np.allclose(
            [[row["cov_xx"], row["cov_xy"]], [row["cov_xy"], row["cov_yy"]]], ped["covariance_xy"], atol=1e-3
        )
        assert row["distance"] == pytest.approx(ped["distance"], abs=1e-3)
        assert np.allclose(row["keypoints_2d"], ped["skeleton"]["uv"], atol=1e-3)
        assert np.allclose(row["keypoints_3d"], ped["skeleton"]["xyz"], atol=1e-3)
        assert row["source"] == ped["source"]
    # one row group per 50 frames, per scene boundary not needed: 80 frames -> 2 groups
    assert pq.ParquetFile(folder / "environment.parquet").num_row_groups == 2


def test_matches_table_reproduces_the_metrics(evaluated):
    folder, result, _ = evaluated
    table = pq.read_table(folder / "matches.parquet")
    assert table.schema.equals(MATCHES_SCHEMA)
    overall = result.metrics.overall
    assert table.num_rows == overall.count > 100
    err = np.hypot(
        np.array(table["pred_x"]) - np.array(table["gt_x"]), np.array(table["pred_y"]) - np.array(table["gt_y"])
    )
    assert np.allclose(err, table["abs_error"].to_numpy())
    assert table["abs_error"].to_numpy().mean() == pytest.approx(overall.abs_error_m, rel=1e-9)
    assert set(table["scene"].to_pylist()) == {"red-light-crossing", "drive-30kmh-sidewalk"}


def test_a_run_stopped_by_a_bad_frame_leaves_a_valid_table_of_the_finished_frames(interrupted):
    table = pq.read_table(interrupted / "environment.parquet")
    frames = {(r["scene"], r["frame"]) for r in table.select(["scene", "frame"]).to_pylist()}
    second = sorted(f for s, f in frames if s == "drive-30kmh-sidewalk")
    assert second[-1] == FailingModel.FAIL_AT - 1
    lines = (interrupted / "environment.jsonl").read_text().splitlines()
    assert table.num_rows == sum(len(json.loads(line)["pedestrians"]) for line in lines)
    assert pq.read_table(interrupted / "matches.parquet").num_rows > 0


@pytest.mark.parametrize("every, message", [(0, "frames_per_row_group must be in"), (10**6, "frames_per_row_group")])
def test_row_group_size_is_range_checked(tmp_path, every, message):
    with pytest.raises(ValueError, match=message):
        EnvironmentTableWriter(tmp_path / "t.parquet", frames_per_row_group=every)


def test_a_missing_extra_is_one_line_naming_the_install_command(tmp_path):
    """pyarrow hidden from the interpreter: the CLI refuses --parquet before running, in one line."""
    import subprocess
    import sys

    code = ("import sys; sys.modules['pyarrow'] = None; sys.modules['pyarrow.parquet'] = None; "
            "from pedenv.cli import main; sys.argv = ['pedenv'] + sys.argv[1:]; main()")
    done = subprocess.run([sys.executable, "-c", code, "demo", "--output", str(tmp_path / "o"), "--parquet"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == ['error: --parquet needs the viz extra: pip install -e ".[viz]"']
    assert not (tmp_path / "o" / "environment.jsonl").exists()
