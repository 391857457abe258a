"""``pedenv run --static`` without ``--calibration``: the estimate refined after the warm-up, for later frames only."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from scene_backend import SceneBackend

from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource


def _run(tmp_path: Path, name: str, frames, folder: Path) -> tuple[dict, list[dict]]:
    from pedenv.apps.run import run_recording

    summary = run_recording(RecordingSource(images=folder, static=True, fps=10.0),
                            OutputOptions(tmp_path / name, video_out=True),
                            PoseOptions(backend="detector-model", detection=None), backend=SceneBackend(frames))
    lines = (tmp_path / name / "environment.jsonl").read_text().splitlines()
    return summary, [json.loads(line) for line in lines]


def test_the_estimate_is_refined_for_later_frames_and_what_was_written_stays(tmp_path: Path,
                                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    import pedenv.apps.calibrate as calibrate
    from pedenv.images import write_image
    from pedenv.synthetic.generator import generate_scenes

    frames = generate_scenes(0, ["static-plaza"], duration_s=7.0)[0].frames
    folder = tmp_path / "images"
    folder.mkdir()
    for frame in frames:
        write_image(folder / f"{frame.index:06d}.jpg", np.full((900, 1600, 3), 90, np.uint8))
    monkeypatch.setattr(calibrate, "WARMUP_MAX_FRAMES", 40)
    monkeypatch.setattr(calibrate, "REFINE_EVERY_FRAMES", 10**6)
    _, fixed = _run(tmp_path, "fixed", frames, folder)
    monkeypatch.setattr(calibrate, "REFINE_EVERY_FRAMES", 15)
    summary, refined = _run(tmp_path, "refined", frames, folder)
    steps = summary["calibration"]["refinements"]
    assert [s["from_frame"] for s in steps] == [0, 55, 70]  # the warm-up's 40 frames, then every 15
    assert steps[0]["observations"] < steps[1]["observations"] < steps[2]["observations"]
    final = summary["calibration"]
    assert final["focal_px"] == steps[-1]["focal_px"] != steps[0]["focal_px"]
    assert final["observations"] == steps[-1]["observations"]
    saved = json.loads((tmp_path / "refined" / "run.json").read_text())["calibration"]
    assert saved["refinements"] == steps
    written = yaml.safe_load((tmp_path / "refined" / "calibration.yaml").read_text())
    assert written["cam_to_vehicle"]["translation"][2] == pytest.approx(final["height_m"], abs=1e-4)
    # frames before the first refit ran with the warm-up's camera: written exactly as without refits
    assert refined[:55] == fixed[:55]
    moved = [p["position"] for line in refined[55:] for p in line["pedestrians"]]
    before = [p["position"] for line in fixed[55:] for p in line["pedestrians"]]
    assert len(moved) == len(before) and moved != before
