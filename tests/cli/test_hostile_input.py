"""Issue 10 at the command line: every bad input or output folder is one ``error:`` line
(exit 2), never a traceback, and a folder never mixes two runs."""

from __future__ import annotations

import json
import sys

import pytest

from pedenv.cli import main

from cli_in_process import pedenv


def one_error_line(code: int, err: str, *fragments: str) -> None:
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])


@pytest.fixture
def a_file(tmp_path):
    path = tmp_path / "taken.txt"
    path.write_text("mine")
    return path


SIMULATE = ["simulate", "--scenes", "1", "--seed", "1"]


@pytest.mark.parametrize("command", [
    SIMULATE,
    ["demo", "--seed", "0"],
    ["evaluate", "--dataset", "synthetic", "--data-root", "SIM"],
])
@pytest.mark.parametrize("where, message", [
    (lambda f: f, "is an existing file"),
    (lambda f: f / "out", "which is a file"),
    (lambda _f: "/proc/pedenv-test/out", "cannot be written"),
])
def test_bad_output_folder_is_one_error_line(monkeypatch, capsys, tmp_path, a_file, command, where, message):
    if "SIM" in command:
        (tmp_path / "sim").mkdir()
        code, _, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", tmp_path / "sim" / "data")
        assert code == 0, err
        command = [str(tmp_path / "sim" / "data") if c == "SIM" else c for c in command]
    code, _, err = pedenv(monkeypatch, capsys, *command, "--output", where(a_file))
    one_error_line(code, err, message)
    assert a_file.read_text() == "mine"


def test_simulate_refuses_an_earlier_run_until_overwrite(monkeypatch, capsys, tmp_path):
    out = tmp_path / "out"
    code, stdout, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", out)
    assert code == 0 and "wrote 1 scenes" in stdout, err
    code, _, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", out)
    one_error_line(code, err, "is not empty; pass --overwrite")
    code, stdout, err = pedenv(monkeypatch, capsys, "simulate", "--scenes", "2", "--seed", "1", "--output", out,
                               "--overwrite")
    assert code == 0 and "wrote 2 scenes" in stdout, err
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["drive-30kmh-sidewalk", "red-light-crossing"]


@pytest.mark.parametrize("args, fragments", [
    (["simulate", "--frame-rate", "0"], ["frame_rate_hz must be in [0.5, 100], got 0.0"]),
    (["simulate", "--scenes", "0"], ["number of scenes must be an integer in [1, 1000], got 0"]),
    (["simulate", "--scenes", "10000"], ["number of scenes must be an integer in [1, 1000], got 10000"]),
    (["bench", "--frames", "0", "--no-pose"], ["number of frames to time must be an integer in [1, 10000], got 0"]),
    (["bench", "--frames", "100000000", "--no-pose"], ["must be an integer in [1, 10000], got 100000000"]),
])
def test_bad_options_are_refused(monkeypatch, capsys, tmp_path, args, fragments):
    code, _, err = pedenv(monkeypatch, capsys, *args, *(["--output", tmp_path / "o"] if args[0] == "simulate" else []))
    one_error_line(code, err, *fragments)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("text, fragment", [
    ('{"paper": {"refine": tru}', "the config is not valid JSON (line 1, column 22"),
    ("\x89PNG\x00\xff\xfe", "the config is not UTF-8 text"),
    ('{"paper": {"person_height_m": 9}}', "paper.person_height_m must be in [0.3, 2.5], got 9"),
    ("[1, 2]", "a config must be a JSON object"),
])
def test_bad_config_names_the_file(monkeypatch, capsys, tmp_path, text, fragment):
    path = tmp_path / "bad.json"
    path.write_bytes(text.encode("latin-1"))
    code, _, err = pedenv(monkeypatch, capsys, "demo", "--config", path, "--output", tmp_path / "o")
    one_error_line(code, err, "bad.json: ", fragment)


def test_truncated_frames_npz_names_the_file(monkeypatch, capsys, tmp_path):
    data = tmp_path / "sim"
    code, _, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", data)
    assert code == 0, err
    (npz,) = data.glob("*/frames.npz")
    npz.write_bytes(npz.read_bytes()[: npz.stat().st_size // 2])
    code, _, err = pedenv(monkeypatch, capsys, "evaluate", "--dataset", "synthetic", "--data-root", data,
                          "--output", tmp_path / "out", "--pose-backend", "ground-truth")
    one_error_line(code, err, "frames.npz: cannot read (truncated or corrupted?)")


def test_a_bug_is_not_hidden_as_an_error_line(monkeypatch, capsys):
    """Only InputError becomes one line: a ValueError from a bug keeps its traceback."""
    import pedenv.apps.bench as bench

    def broken(**_):
        raise ValueError("a bug")

    monkeypatch.setattr(bench, "bench_core", broken)
    monkeypatch.setattr(sys, "argv", ["pedenv", "bench", "--no-pose"])
    with pytest.raises(ValueError, match="a bug"):
        main()


def test_run_loading_error_is_one_line_without_progress_bar(monkeypatch, capsys, tmp_path):
    (tmp_path / "images").mkdir()
    poses = tmp_path / "poses.csv"
    poses.write_text("timestamp,x,y,yaw\n0,0,0,0\n")
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", tmp_path / "images", "--calibration",
                          tmp_path / "missing.yaml", "--ego-poses", poses, "--output", tmp_path / "out")
    one_error_line(code, err, "missing.yaml: cannot read the calibration")
    assert not (tmp_path / "out").exists()


def test_simulated_scene_json_is_strict(monkeypatch, capsys, tmp_path):
    code, _, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", tmp_path / "o")
    assert code == 0, err
    (meta,) = (tmp_path / "o").glob("*/scene.json")
    json.loads(meta.read_text(), parse_constant=lambda c: pytest.fail(f"non-strict JSON token {c}"))


# issue 19 ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("folder", [":x:", ":smile:", "[red]", "[bold]x[/bold]"])
def test_paths_are_printed_as_they_are(monkeypatch, capsys, tmp_path, folder):
    """Rich's emoji codes and markup were on: ``:x:/missing`` was printed as a cross emoji."""
    missing = tmp_path / folder / "missing.json"
    code, _, err = pedenv(monkeypatch, capsys, "demo", "--config", missing, "--output", tmp_path / "o")
    one_error_line(code, err, f"{folder}/missing.json")


LONG = "a" * 300


@pytest.mark.parametrize("command", [SIMULATE, ["evaluate", "--dataset", "synthetic", "--data-root", "SIM",
                                                "--pose-backend", "ground-truth"]])
def test_an_output_name_over_255_bytes_is_one_line(monkeypatch, capsys, tmp_path, command):
    if "SIM" in command:
        code, _, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", tmp_path / "sim")
        assert code == 0, err
        command = [str(tmp_path / "sim") if c == "SIM" else c for c in command]
    code, _, err = pedenv(monkeypatch, capsys, *command, "--output", tmp_path / LONG)
    one_error_line(code, err, "is 300 bytes long; file systems take at most 255")


@pytest.mark.parametrize("flag, target, message", [
    ("--rerun", "INPUT", "the file name must end in .rrd"),
    ("--mcap", "INPUT", "the file name must end in .mcap"),
    ("--rerun", "OUT/environment.jsonl", "the file name must end in .rrd"),
    ("--rerun", "OLD", "exists; pass --overwrite to replace it"),
    ("--mcap", "INPUT/x.mcap", "which is a file"),
])
def test_rerun_and_mcap_never_write_over_inputs(monkeypatch, capsys, tmp_path, flag, target, message):
    """``--mcap rec/ego_poses.csv`` replaced the poses; ``--rerun out/environment.jsonl`` corrupted it (exit 0)."""
    code, _, err = pedenv(monkeypatch, capsys, *SIMULATE, "--output", tmp_path / "sim")
    assert code == 0, err
    (frames,) = (tmp_path / "sim").glob("*/frames.npz")
    before = frames.read_bytes()
    (tmp_path / "old.rrd").write_text("an earlier recording")
    path = target.replace("INPUT", str(frames)).replace("OUT", str(tmp_path / "out")).replace(
        "OLD", str(tmp_path / "old.rrd"))
    code, _, err = pedenv(monkeypatch, capsys, "evaluate", "--dataset", "synthetic", "--data-root", tmp_path / "sim",
                          "--pose-backend", "ground-truth", "--output", tmp_path / "out", flag, path)
    one_error_line(code, err, message)
    assert frames.read_bytes() == before and (tmp_path / "old.rrd").read_text() == "an earlier recording"
    assert not (tmp_path / "out").exists()  # refused before the output folder was made


def test_a_long_name_anywhere_else_is_one_line(monkeypatch, capsys, tmp_path):
    """Any path option (here --data-root) with a name over 255 bytes: one line, not an OSError traceback."""
    code, _, err = pedenv(monkeypatch, capsys, "evaluate", "--dataset", "synthetic", "--data-root", tmp_path / LONG,
                          "--output", tmp_path / "out")
    one_error_line(code, err, "a name in this path is longer than the file system takes (255 bytes)")
