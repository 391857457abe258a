"""The one way settings are checked: type, finiteness, range, count, choice and order.

Every settings class (the sections of :class:`pedenv.config.Config`, the detection and merge
settings, the synthetic scenes' rules) declares each field's range beside its default
(:func:`number`, :func:`count`, :func:`flag`, :func:`choice`) and calls :func:`check_fields` in
its ``__post_init__``, which checks them with the name ``section.field`` as the user writes it
in ``config.json``; checks between fields call the ``check_*`` functions themselves. Each check raises one
:class:`pedenv.errors.InputError` naming that field and the value given, shortened by
:func:`shown` (a config value can be a list of a million numbers; the message stays one
short line). A boolean is never a number and a number never a boolean; NaN and infinity are
refused; every range has an upper bound, so no value can make a run's memory or time unbounded.

A settings class lists the fields earlier versions saved and it no longer has, now module
constants, in a class attribute ``RETIRED`` (field name -> its fixed value).
"""

from __future__ import annotations

import dataclasses
import math
import reprlib
from collections.abc import Sequence
from functools import partial
from typing import Any

from pedenv.errors import InputError

#: At most this many characters of a bad value go into an error message.
MAX_SHOWN_CHARS = 60

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict = 2, 4, 4, 4
_REPR.maxstring, _REPR.maxother = MAX_SHOWN_CHARS, MAX_SHOWN_CHARS


def shown(value: Any) -> str:
    """``repr(value)`` cut to about :data:`MAX_SHOWN_CHARS` characters, never built in full
    (a huge list or integer costs no more than a short one)."""
    if isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 128:
        return f"an integer of {value.bit_length()} bits"
    text = _REPR.repr(value)
    return text if len(text) <= MAX_SHOWN_CHARS else text[: MAX_SHOWN_CHARS - 3] + "..."


def _interval(low: float, high: float, low_open: bool, high_open: bool) -> str:
    return f"{'(' if low_open else '['}{low}, {high}{')' if high_open else ']'}"


def check_bool(name: str, value: Any) -> bool:
    """``value`` if it is a boolean (``true``/``false`` in JSON); 1, 0 and ``"false"`` are refused."""
    if not isinstance(value, bool):
        raise InputError(f"{name} must be true or false, got {shown(value)}")
    return value


def check_number(name: str, value: Any, low: float, high: float, *, low_open: bool = False, high_open: bool = False,
                 off: float | None = None) -> float:
    """``value`` if it is a finite number (int or float, not bool) in ``[low, high]``.

    ``low_open``/``high_open`` exclude that bound; ``off``: a value outside the range that is
    also accepted and means "switched off" (e.g. 0). ``high`` is required: every number a
    setting takes has a documented upper bound.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{name} must be a number, got {shown(value)}")
    if not math.isfinite(value):
        raise InputError(f"{name} must be a finite number, got {shown(value)}")
    if off is not None and value == off:
        return value
    too_low = value <= low if low_open else value < low
    too_high = value >= high if high_open else value > high
    if too_low or too_high:
        prefix = "" if off is None else f"{off} (off) or "
        raise InputError(f"{name} must be {prefix}in {_interval(low, high, low_open, high_open)}, "
                         f"got {shown(value)}")
    return value


def check_count(name: str, value: Any, low: int, high: int) -> int:
    """``value`` if it is an integer (not bool, not 3.0) in ``[low, high]``; ``high`` caps the
    memory or time the count costs."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise InputError(f"{name} must be an integer in [{low}, {high}], got {shown(value)}")
    return value


def check_choice(name: str, value: Any, choices: Sequence[str]) -> str:
    """``value`` if it is one of ``choices``."""
    if not isinstance(value, str) or value not in choices:
        raise InputError(f"{name} must be one of {', '.join(choices)}, got {shown(value)}")
    return value


def check_sequence(name: str, value: Any, max_items: int) -> tuple:
    """``value`` as a tuple if it is a list or tuple of 1 to ``max_items`` entries (their own
    checks are the caller's)."""
    if not isinstance(value, (list, tuple)) or not 1 <= len(value) <= max_items:
        raise InputError(f"{name} must list at least one and at most {max_items} entries, got {shown(value)}")
    return tuple(value)


def check_below(low_name: str, low: float, high_name: str, high: float, *, equal_ok: bool = False) -> None:
    """Two fields that bound one range: ``low`` must lie below ``high`` (or equal it, ``equal_ok``)."""
    if low > high or (low == high and not equal_ok):
        relation = "must not exceed" if equal_ok else "must be below"
        raise InputError(f"{low_name} ({shown(low)}) {relation} {high_name} ({shown(high)})")


#: The key of a field's check in its dataclass field's metadata (:func:`check_fields` runs it).
CHECK = "pedenv.check"


def number(default: float, low: float, high: float, *, low_open: bool = False, high_open: bool = False,
           off: float | None = None) -> float:
    """A settings field holding a finite number in ``[low, high]`` (:func:`check_number`'s options)."""
    return dataclasses.field(default=default, metadata={CHECK: partial(
        check_number, low=low, high=high, low_open=low_open, high_open=high_open, off=off)})


def count(default: int, low: int, high: int) -> int:
    """A settings field holding an integer in ``[low, high]`` (:func:`check_count`)."""
    return dataclasses.field(default=default, metadata={CHECK: partial(check_count, low=low, high=high)})


def flag(default: bool) -> bool:
    """A settings field holding true or false (:func:`check_bool`)."""
    return dataclasses.field(default=default, metadata={CHECK: check_bool})


def choice(default: str, choices: Sequence[str]) -> str:
    """A settings field holding one of ``choices`` (:func:`check_choice`)."""
    return dataclasses.field(default=default, metadata={CHECK: partial(check_choice, choices=choices)})


#: The key of a sequence field's declared range in its dataclass field's metadata
#: (:func:`sequence`); the class checks the entries itself in its ``__post_init__``.
SEQUENCE = "pedenv.sequence"


def sequence(default: tuple, max_items: int, *, low: float | None = None, high: float | None = None,
             low_open: bool = False, choices: Sequence[str] | None = None, increasing: bool = False) -> Any:
    """A settings field holding a tuple of 1 to ``max_items`` entries, each a number in ``[low,
    high]`` (``low_open``: above ``low``; ``increasing``: strictly increasing) or one of
    ``choices``. The range is declared for readers (:mod:`pedenv.settings_draw`, the docs); the
    class checks the entries itself."""
    return dataclasses.field(default=default, metadata={SEQUENCE: {
        "max_items": max_items, "low": low, "high": high, "low_open": low_open, "choices": choices,
        "increasing": increasing}})


def check_fields(section: str, settings: Any) -> None:
    """Check every field of the dataclass instance ``settings`` declared with :func:`number`,
    :func:`count`, :func:`flag` or :func:`choice`, in field order, naming it ``section.field``."""
    for f in dataclasses.fields(settings):
        check = f.metadata.get(CHECK)
        if check is not None:
            check(f"{section}.{f.name}", getattr(settings, f.name))

