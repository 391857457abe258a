"""The one set of validators: each bad value gives one InputError naming the field and a
shortened value."""

from __future__ import annotations

import dataclasses
import importlib
import math

import pytest

from pedenv.errors import InputError
from pedenv.validation import (
    MAX_SHOWN_CHARS,
    check_below,
    check_bool,
    check_choice,
    check_count,
    check_number,
    check_sequence,
    shown,
)


@pytest.mark.parametrize("call, message", [
    (lambda: check_bool("paper.refine", "false"), "paper.refine must be true or false, got 'false'"),
    (lambda: check_bool("paper.refine", 1), "paper.refine must be true or false, got 1"),
    (lambda: check_bool("paper.refine", None), "paper.refine must be true or false, got None"),
    (lambda: check_number("s.x", True, 0.0, 1.0), "s.x must be a number, got True"),
    (lambda: check_number("s.x", "1.5", 0.0, 2.0), "s.x must be a number, got '1.5'"),
    (lambda: check_number("s.x", math.nan, 0.0, 1.0), "s.x must be a finite number, got nan"),
    (lambda: check_number("s.x", -math.inf, 0.0, 1.0), "s.x must be a finite number, got -inf"),
    (lambda: check_number("s.x", 1.0, -1.0, 1.0, high_open=True), "s.x must be in [-1.0, 1.0), got 1.0"),
    (lambda: check_number("s.x", 0.0, 0.0, 5.0, low_open=True), "s.x must be in (0.0, 5.0], got 0.0"),
    (lambda: check_number("s.x", 0.5, 1.0, 100.0, low_open=True, off=0.0),
     "s.x must be 0.0 (off) or in (1.0, 100.0], got 0.5"),
    (lambda: check_count("s.n", 0, 1, 300), r"s.n must be an integer in [1, 300], got 0"),
    (lambda: check_count("s.n", 1e9, 1, 300), r"s.n must be an integer in [1, 300], got 1000000000.0"),
    (lambda: check_count("s.n", 3.0, 1, 300), r"s.n must be an integer in [1, 300], got 3.0"),
    (lambda: check_count("s.n", True, 0, 300), r"s.n must be an integer in [0, 300], got True"),
    (lambda: check_count("s.n", 10 ** 5000, 0, 300),
     "s.n must be an integer in [0, 300], got an integer of 16610 bits"),
    (lambda: check_choice("s.mode", "slow", ("fast", "far")), "s.mode must be one of fast, far, got 'slow'"),
    (lambda: check_choice("s.mode", ["far"], ("fast", "far")), "s.mode must be one of fast, far, got ['far']"),
    (lambda: check_sequence("s.cues", [], 3), "s.cues must list at least one and at most 3 entries, got []"),
    (lambda: check_sequence("s.cues", "abc", 3), "s.cues must list at least one and at most 3 entries, got 'abc'"),
    (lambda: check_below("s.near", 5, "s.far", 5), "s.near (5) must be below s.far (5)"),
    (lambda: check_below("s.min", 6, "s.max", 5, equal_ok=True), "s.min (6) must not exceed s.max (5)"),
])
def test_bad_values_give_one_clear_error(call, message):
    with pytest.raises(InputError) as info:
        call()
    assert str(info.value) == message


@pytest.mark.parametrize("call, expected", [
    (lambda: check_bool("s.b", False), False),
    (lambda: check_number("s.x", 1, 0.0, 1.0), 1),
    (lambda: check_number("s.x", 0.0, 1.0, 100.0, low_open=True, off=0.0), 0.0),
    (lambda: check_count("s.n", 300, 1, 300), 300),
    (lambda: check_sequence("s.cues", ["a", "b"], 3), ("a", "b")),
    (lambda: check_below("s.min", 5, "s.max", 5, equal_ok=True), None),
])
def test_good_values_pass(call, expected):
    assert call() == expected


@pytest.mark.parametrize("value", [list(range(10 ** 6)), "x" * 10 ** 7, {str(i): i for i in range(10 ** 5)},
                                   [[[[[[list(range(1000))]]]]]]])
def test_a_huge_value_is_shown_short(value):
    assert len(shown(value)) <= MAX_SHOWN_CHARS
    with pytest.raises(InputError) as info:
        check_number("s.x", value, 0.0, 1.0)
    assert len(str(info.value)) < 100


#: Where each section's retired fields live now: the modules that hold their constants.
RETIRED_HOMES = {
    "tracking": ("pedenv.tracking.recall", "pedenv.tracking.tracker", "pedenv.config_tracking"),
    "kalman": ("pedenv.kalman",),
    "paper": ("pedenv.localization.paper",),
    "fused": ("pedenv.localization.fused.ground", "pedenv.localization.fused.cue",
              "pedenv.localization.fused.triangulation", "pedenv.localization.fused.locator"),
    "behaviour": ("pedenv.behaviour.orientation", "pedenv.behaviour.motion_state", "pedenv.behaviour.estimator",
                  "pedenv.behaviour.ego_path", "pedenv.behaviour.conflict"),
}


@pytest.mark.parametrize("section", sorted(RETIRED_HOMES))
def test_each_retired_field_is_a_constant_holding_its_fixed_value(section):
    """A config saved before may name a retired field at its fixed value: that value is the
    constant's (imported where it is used, the same everywhere), and the name is a field no more."""
    from pedenv.config import SECTIONS

    kind = SECTIONS[section]
    fields = {f.name for f in dataclasses.fields(kind)}
    modules = [importlib.import_module(m) for m in RETIRED_HOMES[section]]
    assert kind.RETIRED
    for name, fixed in kind.RETIRED.items():
        assert name not in fields, f"{section}.{name} is both a field and retired"
        values = [getattr(m, name.upper()) for m in modules if hasattr(m, name.upper())]
        assert set(values) == {fixed}, f"{section}.{name}: {values} in {RETIRED_HOMES[section]}, retired at {fixed}"
