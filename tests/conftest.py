"""Fixtures shared by the tests (helpers live in ``standing_people.py``): a camera, real photographs
and the ONNX pose models prepared once into a temp cache."""

import os
from pathlib import Path

import pytest

from pedenv.records import Camera

os.environ.setdefault("YOLO_OFFLINE", "1")


@pytest.fixture
def camera() -> Camera:
    return Camera.from_fov(1600, 900, 64.5, height_m=1.5)


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
