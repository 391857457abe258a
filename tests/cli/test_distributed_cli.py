"""``pedenv evaluate --executor ray``: an unreachable cluster is one line; Ctrl-C leaves no Ray process behind."""

import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from pedenv.apps.distributed import CHECKPOINT, SCENES_FOLDER
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.storage import write_scenes

from cli_in_process import pedenv


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def stored_scenes(tmp_path_factory):
    """Three full built-in scenes (seed 0) as the synthetic dataset on disk."""
    root = tmp_path_factory.mktemp("scenes")
    write_scenes(generate_scenes(0, list(SCENARIOS[:3])), root)
    return root


@pytest.mark.ray
def test_an_unreachable_ray_address_is_one_line_and_nothing_runs(monkeypatch, capsys, tmp_path, stored_scenes):
    address = f"127.0.0.1:{_closed_port()}"
    code, out, err = pedenv(monkeypatch, capsys, "evaluate", "--dataset", "synthetic", "--data-root", stored_scenes,
                            "--output", tmp_path / "out", "--executor", "ray", "--address", address)
    assert code == 2 and out == ""
    assert err.startswith(f"error: Ray cluster at {address} is not reachable") and err.count("\n") == 1
    assert not (tmp_path / "out" / "metrics.json").exists()


@pytest.mark.parametrize("flags, message", [
    (["--executor", "dask"], "unknown executor 'dask'; valid: serial, ray"),
    (["--address", "10.0.0.1:6379"], "--address and --workers apply to --executor ray"),
    (["--workers", "2"], "--address and --workers apply to --executor ray"),
    (["--executor", "ray", "--object-store-memory", "10"],
     "--object-store-memory must be at least 78643200 bytes (Ray's minimum), got 10"),
    (["--executor", "ray", "--method", "both"], "--method both run in the serial in-process evaluation only"),
    (["--resume", "--parquet"], "--parquet run in the serial in-process evaluation only"),
])
def test_flags_that_do_not_go_together_are_one_line(monkeypatch, capsys, tmp_path, stored_scenes, flags, message):
    code, _, err = pedenv(monkeypatch, capsys, "evaluate", "--dataset", "synthetic", "--data-root", stored_scenes,
                          "--output", tmp_path / "out", *flags)
    assert code == 2 and err.startswith(f"error: {message}") and err.count("\n") == 1


def _processes_under(folder: str) -> list[str]:
    """Command lines of the running processes that name ``folder`` (a Ray session's raylet, GCS, workers)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            cmdline = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if proc.name.isdigit() and folder in cmdline:
            found.append(f"{proc.name}: {cmdline[:160]}")
    return found


#: Scenes of the Ctrl-C test: the three stored ones and copies of them (hard links, new names).
MANY_SCENES = 60


@pytest.fixture
def many_scenes(tmp_path, stored_scenes):
    """:data:`MANY_SCENES` scenes: far more work than 2 workers finish between the first checkpoint
    and the SIGINT (tenths of a second), so the run cannot end on its own before the signal."""
    root = tmp_path / "many"
    originals = sorted(p for p in stored_scenes.iterdir() if (p / "scene.json").is_file())
    for k in range(MANY_SCENES):
        source = originals[k % len(originals)]
        folder = root / f"{source.name}-{k:02d}"
        folder.mkdir(parents=True)
        os.link(source / "frames.npz", folder / "frames.npz")
        meta = json.loads((source / "scene.json").read_text())
        meta["frame_scenes"] = [folder.name] * len(meta["frame_scenes"])
        (folder / "scene.json").write_text(json.dumps({**meta, "name": folder.name}))
    return root


@pytest.mark.ray
@pytest.mark.slow
def test_ctrl_c_keeps_the_finished_scenes_and_leaves_no_ray_process(tmp_path, many_scenes):
    ray_root = tempfile.mkdtemp(prefix="pedenv-ray-", dir="/tmp")  # short: Ray's socket paths have a length limit
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "pedenv", "evaluate", "--dataset", "synthetic", "--data-root",
                             str(many_scenes), "--output", str(out), "--executor", "ray", "--workers", "2",
                             "--pose-backend", "ground-truth"],  # the quickest scenes: the first checkpoint comes soon
                            env={**os.environ, "RAY_TMPDIR": ray_root}, stdout=subprocess.DEVNULL,
                            stderr=(tmp_path / "stderr.txt").open("w"))  # a file: a full pipe would block the run
    checkpoints = f"{SCENES_FOLDER}/*/{CHECKPOINT}"
    deadline = time.time() + 600
    while time.time() < deadline and proc.poll() is None and not list(out.glob(checkpoints)):
        time.sleep(0.2)  # until the first scene is done; the others still run
    assert proc.poll() is None and _processes_under(ray_root), "the run ended before Ctrl-C"
    assert list(out.glob(checkpoints)), "no scene finished in 600 s (a machine that busy cannot run this test)"
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=120)
    err = (tmp_path / "stderr.txt").read_text()
    assert proc.returncode == 130 and "Traceback" not in err, err  # 130: stopped by the signal
    left = _processes_under(ray_root)
    for _ in range(50):  # Ray's processes exit asynchronously after ray.shutdown()
        if not left:
            break
        time.sleep(0.2)
        left = _processes_under(ray_root)
    assert left == []
    finished = list(out.glob(checkpoints))
    assert 1 <= len(finished) < MANY_SCENES  # interrupted: some scenes kept, not all run
    assert all((p.parent / "environment.jsonl").stat().st_size > 0 for p in finished)
