"""``pedenv run --static`` without ``--calibration``: the camera estimated in the warm-up, then the run."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scene_backend import SceneBackend

from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource


def test_a_static_run_without_calibration_estimates_it_and_widens_the_covariances(tmp_path: Path) -> None:
    from pedenv.apps.run import run_recording
    from pedenv.images import write_image
    from pedenv.synthetic.generator import generate_scenes

    frames = generate_scenes(0, ["static-plaza"], duration_s=6.0)[0].frames
    folder = tmp_path / "images"
    folder.mkdir()
    for frame in frames:
        write_image(folder / f"{frame.index:06d}.jpg", np.full((900, 1600, 3), 90, np.uint8))
    source = RecordingSource(images=folder, static=True, fps=10.0)
    summary = run_recording(source, OutputOptions(tmp_path / "run", video_out=True),
                            PoseOptions(backend="detector-model", detection=None), backend=SceneBackend(frames))
    out = tmp_path / "run"
    assert summary["frames_done"] == len(frames) == 60
    assert summary["calibration"]["focal_px"] == pytest.approx(frames[0].camera.intrinsics[0, 0], rel=0.1)
    assert summary["calibration"]["height_m"] == pytest.approx(6.0, rel=0.1)
    with pytest.warns(UserWarning, match="estimated"):
        from pedenv.recordings.footage import load_calibration

        load_calibration(out / "calibration.yaml")
    from pedenv.config import Config

    assert json.loads((out / "config.json").read_text())["fused"] == json.loads(json.dumps(Config().to_dict()["fused"]))
    assert json.loads((out / "run.json").read_text())["calibration"]["people"] >= 5
    lines = (out / "environment.jsonl").read_text().splitlines()
    assert len(lines) == 60 and any(json.loads(line)["pedestrians"] for line in lines[-5:])
    # the same frames with the estimate given as a file: the same positions, the calibration's spread not added
    given = RecordingSource(images=folder, static=True, fps=10.0, calibration=out / "calibration.yaml")
    with pytest.warns(UserWarning, match="estimated"):
        run_recording(given, OutputOptions(tmp_path / "given", video_out=True),
                      PoseOptions(backend="detector-model", detection=None), backend=SceneBackend(frames))
    widened = [json.loads(line)["pedestrians"] for line in lines]
    given_lines = (tmp_path / "given" / "environment.jsonl").read_text().splitlines()
    plain = [json.loads(line)["pedestrians"] for line in given_lines]
    extra = []
    for a, b in zip(widened, plain):
        assert [p["track_id"] for p in a] == [p["track_id"] for p in b]
        for p, q in zip(a, b):
            np.testing.assert_allclose(p["position"], q["position"], atol=1e-3)
            extra.append(np.array(p["covariance_xy"]) - np.array(q["covariance_xy"]))
    assert len(extra) > 100 and min(np.linalg.eigvalsh(e).min() for e in extra) > -2e-3  # JSON Lines keep 3 decimals
    assert np.median([np.trace(e) for e in extra]) > 1e-3  # m^2: the estimate's spread, one error for all
