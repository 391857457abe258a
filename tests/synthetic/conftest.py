"""Scenes generated once per test session."""

from __future__ import annotations

import pytest

from pedenv.records import Scene
from pedenv.synthetic import generate_scenes


@pytest.fixture(scope="session")
def default_scenes() -> list[Scene]:
    """The whole default set: all scenarios, 10 Hz, flat ground, seed 0."""
    return generate_scenes(0)


@pytest.fixture(scope="session")
def terrain_scenes() -> list[Scene]:
    """All scenarios on rolling terrain, 6 s each, seed 1."""
    return generate_scenes(1, duration_s=6.0, terrain=True)
