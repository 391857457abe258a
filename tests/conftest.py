"""Fixtures shared by the core tests (helpers live in ``standing_people.py``)."""

import pytest

from pedenv.records import Camera


@pytest.fixture
def camera() -> Camera:
    return Camera.from_fov(1600, 900, 64.5, height_m=1.5)
