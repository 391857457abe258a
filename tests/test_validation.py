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
    without_removed,
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


def _removed_sections():
    from pedenv.config import SECTIONS

    return [(name, kind) for name, kind in SECTIONS.items() if getattr(kind, "REMOVED", None)]


@pytest.mark.parametrize("section, kind", _removed_sections())
def test_each_removed_field_names_the_constant_that_holds_its_value(section, kind):
    fields = {f.name for f in dataclasses.fields(kind)}
    for name, where in kind.REMOVED.items():
        assert name not in fields, f"{section}.{name} is both a field and removed"
        target, value = where.split(" (")[0].split(" = ")
        module, constant = target.rsplit(".", 1)
        assert getattr(importlib.import_module(module), constant) == float(value), where


def test_a_saved_section_with_removed_fields_loads_with_one_warning_each():
    from pedenv.config_tracking import TrackingConfig

    saved = {"max_misses": 5, "camera_check": 0.5, "memory_gate": 9.21}
    with pytest.warns(UserWarning) as caught:
        values = without_removed("config.tracking", TrackingConfig, saved)
    assert values == {"max_misses": 5} and saved["camera_check"] == 0.5  # the saved dict is not changed
    assert sorted(str(w.message) for w in caught) == [
        "config.tracking.camera_check is no longer a setting: the saved 0.5 is ignored "
        "(pedenv.tracking.recall.CAMERA_CHECK = 0.34)",
        "config.tracking.memory_gate is no longer a setting: the saved 9.21 is ignored "
        "(pedenv.tracking.recall.MEMORY_GATE = 9.21)"]
    assert TrackingConfig(**values).max_misses == 5
    unknown = {"nonsense": 1}
    assert without_removed("config.tracking", TrackingConfig, unknown) is unknown  # left for the caller to refuse
