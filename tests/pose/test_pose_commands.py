"""The ``pedenv models prepare`` and ``pedenv detect`` commands."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from pedenv.cli import app

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model]


def test_models_prepare_exports_one_dynamic_model_once_offline(tmp_path, monkeypatch):
    monkeypatch.setenv("PEDENV_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("YOLO_OFFLINE", "1")
    first = CliRunner().invoke(app, ["models", "prepare"])
    assert first.exit_code == 0, first.output
    lines = [line.split("\t") for line in first.stdout.splitlines() if "\t" in line]
    assert [(size, state) for size, state, _ in lines] == [("dynamic", "exported")]
    path = lines[0][2]
    assert path.startswith(str(tmp_path / "cache" / "models")) and path.endswith("_dynamic.onnx")
    assert "AutoUpdate" not in first.output and "pip install" not in first.output
    from pedenv.pose.models import check_onnx_file

    assert check_onnx_file(Path(path)) == (None, None)  # any input size runs without re-exporting
    again = CliRunner().invoke(app, ["models", "prepare"])
    assert again.exit_code == 0 and "dynamic\tcached" in again.stdout


def test_detect_writes_json_and_images(tmp_path, use_pose_cache, photo):
    result = CliRunner().invoke(app, ["detect", str(photo("zidane.jpg")), str(photo("bus.jpg")),
                                      "--output", str(tmp_path / "out"), "--pose-input-size", "384x640"])
    assert result.exit_code == 0, result.output
    data = json.loads((tmp_path / "out" / "detections.json").read_text())["images"]
    assert [d["file"].rsplit("/", 1)[-1] for d in data] == ["zidane.jpg", "bus.jpg"]
    assert len(data[0]["persons"]) == 2 and data[0]["width"] == 1280
    assert (tmp_path / "out" / "zidane_pose.png").is_file() and (tmp_path / "out" / "bus_pose.png").is_file()


def test_detect_unknown_backend_lists_valid_ones(tmp_path, photo):
    result = CliRunner().invoke(
        app, ["detect", str(photo("bus.jpg")), "--output", str(tmp_path), "--pose-backend", "yolo"]
    )
    assert isinstance(result.exception, ValueError) and "valid: ground-truth" in str(result.exception)
