"""Fixtures for the pose tests: real photographs and the ONNX models prepared once into a temp cache."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

os.environ.setdefault("YOLO_OFFLINE", "1")


def ultralytics_asset(name: str) -> Path:
    """A test photograph shipped with ultralytics (``bus.jpg``: 4 people, ``zidane.jpg``: 2)."""
    import importlib.util

    spec = importlib.util.find_spec("ultralytics")
    if spec is None:
        pytest.fail(
            "ultralytics is not installed (pip install 'pedenv[ultralytics]'); deselect with -m 'not ultralytics'"
        )
    return Path(list(spec.submodule_search_locations)[0]) / "assets" / name


@pytest.fixture(scope="session")
def photo():
    """``photo(name)``: the path of an ultralytics test photograph."""
    return ultralytics_asset


@pytest.fixture(scope="session")
def pose_cache(tmp_path_factory) -> Path:
    """A cache folder holding the ONNX exports (640x640 and 384x640) of yolo11n-pose.pt."""
    from pedenv.pose.models import prepare_models

    cache = tmp_path_factory.mktemp("pedenv-cache")
    prepare_models(cache=cache)
    return cache


@pytest.fixture
def use_pose_cache(pose_cache, monkeypatch) -> Path:
    """Point ``$PEDENV_CACHE`` at the prepared models for one test."""
    monkeypatch.setenv("PEDENV_CACHE", str(pose_cache))
    return pose_cache
