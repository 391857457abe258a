"""``pedenv demo`` stopped by SIGTERM part-way: every output it was writing stays readable."""

import json
import signal
import subprocess
import sys
import time

import pyarrow.parquet as pq
import pytest
import rerun.dataframe as rrd
from mcap.reader import make_reader


@pytest.mark.slow
def test_sigterm_leaves_every_output_valid(tmp_path):
    out = tmp_path / "demo"
    proc = subprocess.Popen([sys.executable, "-m", "pedenv", "demo", "--output", str(out), "--parquet",
                             "--rerun", str(out / "demo.rrd"), "--mcap", str(out / "demo.mcap")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    jsonl = out / "environment.jsonl"
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None:  # into the second scene, so that files have been rotated
        if jsonl.is_file() and len(jsonl.read_text().splitlines()) > 260:
            break
        time.sleep(0.5)
    assert proc.poll() is None, proc.stderr.read()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "Traceback" not in err
    lines = [json.loads(line) for line in jsonl.read_text().splitlines()]
    done = len(lines)
    rows = pq.read_table(out / "environment.parquet").num_rows
    assert abs(rows - sum(len(line["pedestrians"]) for line in lines)) <= len(lines[-1]["pedestrians"]) + 40
    with (out / "demo.mcap").open("rb") as f:
        records = sum(1 for _ in make_reader(f).iter_messages(topics=["/environment"]))
    assert done - 1 <= records <= done + 1
    first = rrd.load_recording(out / "demo-red-light-crossing.rrd").view(index="frame", contents="/**")
    assert first.select().read_all().num_rows == 200
    second = rrd.load_recording(out / "demo-drive-30kmh-sidewalk.rrd").view(index="frame", contents="/**")
    assert abs(second.select().read_all().num_rows - (done - 200)) <= 1
