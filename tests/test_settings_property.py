"""Settings that are accepted work (issue 32): every saved setting of every section of
``pedenv.config.SECTIONS`` drawn at its minimum, its maximum and random values inside its
declared range (:mod:`pedenv.settings_draw`, seeded), the config built, and the model run on
three built-in scenes (a turning ego, a crowd, a static camera; 2 s each at 10 Hz): no exception
but InputError, no NaN or infinity in the state, no hang. CI runs a share of the
configurations; ``benchmarks/settings_property.py`` runs all of them (and the detection modes on
real images)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pedenv import validation
from pedenv.config import SECTIONS
from pedenv.settings_draw import build, draw_config, draw_field, run_model, scene_frames

#: Configurations in CI: seeds 0..CI_CONFIGS-1 (seed 0 every field at its minimum, 1 at its maximum).
CI_CONFIGS = 24


@pytest.fixture(scope="module")
def frames():
    return scene_frames()


def _draw(seed: int) -> dict:
    return draw_config(np.random.default_rng(seed), {0: "min", 1: "max"}.get(seed))


@pytest.mark.parametrize("seed", range(CI_CONFIGS))
def test_a_drawn_config_runs_without_error_nan_or_hang(seed, frames):
    config, reset, refused = build(_draw(seed))
    assert config is not None, refused  # interacting values are reset one by one until accepted
    done, _, failure = run_model(config, frames)
    assert failure == "", (seed, failure)
    assert done > 0


def test_every_field_of_my_sections_has_a_readable_range():
    """The sections whose ranges are declared for readers: each field can be drawn at its minimum
    and maximum (no field silently kept at its default)."""
    rng = np.random.default_rng(0)
    for name in ("tracking", "kalman", "paper", "fused", "behaviour"):
        for field in dataclasses.fields(SECTIONS[name]):
            for how in ("min", "max"):
                assert draw_field(rng, field, how) is not draw_field(rng, field, "default"), f"{name}.{field.name}"


def test_the_extremes_are_accepted_and_differ_from_the_defaults():
    lowest, highest = build(_draw(0))[0], build(_draw(1))[0]
    assert lowest is not None and highest is not None
    assert lowest.tracking.max_misses == 1 and highest.tracking.max_misses == 300
    assert lowest.fused.history_length == 1 and highest.fused.history_length == 100
    assert lowest.behaviour.horizons_s == pytest.approx((1e-5,)) and len(highest.behaviour.horizons_s) >= 1


def test_a_config_whose_values_contradict_is_reset_field_by_field():
    data = {"behaviour": {"walk_exit_mps": 1.0, "walk_enter_mps": 0.5}}
    config, reset, refused = build(data)
    assert refused == "" and reset == ["behaviour.walk_exit_mps"]
    assert (config.behaviour.walk_exit_mps, config.behaviour.walk_enter_mps) == (0.3, 0.5)


def test_a_range_declared_as_a_sequence_is_read():
    spec = validation.sequence((1.0,), 3, low=0.0, high=2.0, low_open=True, increasing=True).metadata
    assert spec[validation.SEQUENCE]["max_items"] == 3
