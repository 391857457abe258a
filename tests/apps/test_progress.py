"""The one progress bar: as a callback for recordings and inside the evaluation over scenes."""

import io

from rich.console import Console

from pedenv.apps.evaluate import run_evaluation
from pedenv.apps.progress import progress_callback
from pedenv.datasets.memory import MemoryDataset
from pedenv.synthetic import generate_scenes


def _console() -> tuple[Console, io.StringIO]:
    out = io.StringIO()
    return Console(file=out, width=100, force_terminal=False), out


def test_callback_shows_frames_done_of_total():
    console, out = _console()
    with progress_callback("frames", console=console) as progress:
        progress(0, 0)  # total not known yet
        progress(7, 10)
    text = out.getvalue()
    assert text.startswith("frames") and "7/10" in text


def test_evaluation_draws_one_task_per_scene(capsys):
    data = MemoryDataset(generate_scenes(0, ["standing-pedestrians"], duration_s=1.0), name="tiny")
    frames = len(list(data.frames("standing-pedestrians")))
    run_evaluation(data, pose_backend="ground-truth", progress=True)
    shown = capsys.readouterr().out
    assert "standing-pedestrians" in shown and f"{frames}/{frames}" in shown


def test_disabled_evaluation_draws_nothing(capsys):
    data = MemoryDataset(generate_scenes(0, ["standing-pedestrians"], duration_s=1.0), name="tiny")
    run_evaluation(data, pose_backend="ground-truth", progress=False)
    assert capsys.readouterr().out == ""
