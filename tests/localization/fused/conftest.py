"""Fixtures of the fused tests (the hand-built frames live in ``fused_frames``)."""

import pytest

from fused_frames import make_frame


@pytest.fixture
def frame_factory():
    return make_frame
