"""Saved settings drawn inside their declared ranges: the settings property test
(``tests/test_settings_property.py``) and its benchmark (``benchmarks/settings_property.py``).

Every field of every section of :data:`pedenv.config.SECTIONS` is read generically from its
declaration (:mod:`pedenv.validation`): a :func:`~pedenv.validation.number`,
:func:`~pedenv.validation.count`, :func:`~pedenv.validation.flag`,
:func:`~pedenv.validation.choice` or :func:`~pedenv.validation.sequence` field carries its range;
a nested settings dataclass (``detection.stream``) is drawn field by field; any other field keeps
its default. A field is drawn at its minimum, its maximum, a random value inside its range, its
``off`` value or its default. Values that interact (``walk_exit_mps < walk_enter_mps``) are drawn
independently: :func:`build` resets the first drawn field an :class:`~pedenv.errors.InputError`
names to its default, one at a time, until the config is accepted, and reports which.
"""

from __future__ import annotations

import dataclasses
import math
import re
import signal
from collections.abc import Iterable
from functools import partial
from typing import Any

import numpy as np

from pedenv import validation
from pedenv.config import SECTIONS, Config
from pedenv.errors import InputError
from pedenv.localization import LOCATORS
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Frame

#: The built-in scenes every drawn config runs on: a turning ego, a crowd, a static camera.
PROPERTY_SCENES = ("turn-intersection", "crowd", "static-plaza")
#: A configuration that has not finished its frames after this long (s) counts as a hang: a
#: guard many times the slowest configuration's time, not a speed check.
HANG_LIMIT_S = 120
#: How a field is drawn, and the weight of each in a mixed draw.
DRAWS = {"min": 0.2, "max": 0.2, "uniform": 0.45, "off": 0.05, "default": 0.1}
#: An open bound is approached to this share of the range.
OPEN_STEP = 1e-6
#: Most rounds of resetting the fields an error names before a draw counts as refused.
MAX_REPAIRS = 40
_KEEP = object()
_NAMES = re.compile(r"\b((?:[a-z_]+\.)+[a-z_]+)\b")
_WORDS = re.compile(r"(?<![.\w])([a-z]+_[a-z_]+)\b")


def _number(rng: np.random.Generator, how: str, low: float, high: float, low_open: bool, high_open: bool,
            off: float | None) -> Any:
    span = high - low
    lo = low + OPEN_STEP * span if low_open else low
    hi = high - OPEN_STEP * span if high_open else high
    if how == "off":
        return _KEEP if off is None else off
    if how == "min":
        return lo
    if how == "max":
        return hi
    if lo > 0 and hi / lo > 100 and rng.random() < 0.5:  # log-uniform: small values too
        return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
    return float(rng.uniform(lo, hi))


def draw_field(rng: np.random.Generator, field: dataclasses.Field, how: str) -> Any:
    """A value of ``field`` drawn ``how`` (a key of :data:`DRAWS`), or ``_KEEP`` (its default)."""
    if how == "default":
        return _KEEP
    check = field.metadata.get(validation.CHECK)
    spec = field.metadata.get(validation.SEQUENCE)
    if check is validation.check_bool:
        return {"min": False, "max": True}.get(how, bool(rng.random() < 0.5))
    if isinstance(check, partial) and check.func is validation.check_number:
        k = check.keywords
        return _number(rng, how, k["low"], k["high"], k.get("low_open", False), k.get("high_open", False),
                       k.get("off"))
    if isinstance(check, partial) and check.func is validation.check_count:
        k = check.keywords
        return {"min": k["low"], "max": k["high"]}.get(how, int(rng.integers(k["low"], k["high"] + 1)))
    if isinstance(check, partial) and check.func is validation.check_choice:
        return str(rng.choice(list(check.keywords["choices"])))
    if spec is not None:
        return _sequence(rng, spec, how)
    return _KEEP  # a range this module cannot read: the default


def _sequence(rng: np.random.Generator, spec: dict, how: str) -> Any:
    n = {"min": 1, "max": spec["max_items"]}.get(how, int(rng.integers(1, spec["max_items"] + 1)))
    if spec["choices"] is not None:
        return [str(c) for c in rng.permutation(list(spec["choices"]))[:n]]
    low, high = spec["low"], spec["high"]
    if low is None or high is None:
        return _KEEP
    values = [_number(rng, "uniform", low, high, spec["low_open"], False, None) for _ in range(n)]
    if how == "min":
        values = [_number(rng, "min", low, high, spec["low_open"], False, None)]
    if how == "max":
        values[-1] = high
    if spec["increasing"]:
        values = sorted(set(values))
    return values


def draw_section(rng: np.random.Generator, kind: type, how: str | None = None) -> dict:
    """The drawn fields of the settings class ``kind`` (those kept at their default left out);
    ``how`` None draws each field its own way (:data:`DRAWS`' weights)."""
    out: dict[str, Any] = {}
    ways, weights = list(DRAWS), np.array(list(DRAWS.values()))
    for field in dataclasses.fields(kind):
        way = how or str(rng.choice(ways, p=weights / weights.sum()))
        default = field.default
        if dataclasses.is_dataclass(default) and not isinstance(default, type):
            value: Any = draw_section(rng, type(default), how)
        else:
            value = draw_field(rng, field, way)
        if value is not _KEEP:
            out[field.name] = value
    return out


def draw_config(rng: np.random.Generator, how: str | None = None) -> dict:
    """A config as ``config.json`` holds it: a method and every section drawn (:func:`draw_section`)."""
    data: dict[str, Any] = {"method": str(rng.choice(sorted(LOCATORS)))}
    for name, kind in SECTIONS.items():
        data[name] = draw_section(rng, kind, how)
    return data


def _drop(data: dict, path: str) -> bool:
    """Remove the drawn value at ``section.field`` (or ``section.nested.field``); whether there was one."""
    *parents, leaf = path.split(".")
    node: Any = data
    for key in parents:
        node = node.get(key) if isinstance(node, dict) else None
    if isinstance(node, dict) and leaf in node:
        del node[leaf]
        return True
    return False


def build(data: dict) -> tuple[Config | None, list[str], str]:
    """The config of the drawn ``data`` (changed in place: each field an error names is reset to
    its default), the fields reset, and the last error if it was refused (``config`` None)."""
    reset: list[str] = []
    for _ in range(MAX_REPAIRS):
        try:
            return Config.from_dict(data), reset, ""
        except InputError as exc:
            message = str(exc)
            paths = [m.removeprefix("config.") for m in _NAMES.findall(message)]
            # a field named bare beside a named one of its section ("... the context track_margin")
            parents = {p.rsplit(".", 1)[0] for p in paths}
            paths += [f"{parent}.{word}" for parent in parents for word in _WORDS.findall(message)]
            named = next((p for p in dict.fromkeys(paths) if _drop(data, p)), None)  # one at a time
            if named is None:
                return None, reset, message
            reset.append(named)
    return None, reset, "too many fields reset"


def nonfinite(state: Any) -> str:
    """The first field of a model state's pedestrians (and their behaviour) holding NaN or
    infinity, or ''."""
    peds = state.pedestrians
    for name in ("positions", "velocities", "covariances", "keypoints", "confidences", "boxes", "keypoints_3d",
                 "distances"):
        if not np.isfinite(np.asarray(getattr(peds, name), float)).all():
            return name
    if peds.behaviour is not None:
        for f in dataclasses.fields(peds.behaviour):
            if not np.isfinite(np.asarray(getattr(peds.behaviour, f.name), float)).all():
                return f"behaviour.{f.name}"
    return ""


def scene_frames(duration_s: float = 2.0, names: Iterable[str] = PROPERTY_SCENES, seed: int = 0
                 ) -> dict[str, list[Frame]]:
    """The frames of the built-in scenes ``names``, ``duration_s`` long at 10 Hz, with the
    ``detector-model`` backend's detections."""
    from pedenv.synthetic import generate_scenes
    from pedenv.synthetic.detector import DetectorModel

    detector = DetectorModel(seed)
    return {s.name: [dataclasses.replace(f, detections=detector(f)) for f in s.frames]
            for s in generate_scenes(seed, list(names), duration_s=duration_s)}


def _hang(_signum: int, _frame: Any) -> None:
    raise TimeoutError(f"no end after {HANG_LIMIT_S} s")


def run_model(config: Config, frames: dict[str, list[Frame]]) -> tuple[int, int, str]:
    """Run a fresh model of ``config`` over each scene's frames: (frames run, frames refused with
    an InputError, the first failure: an exception but InputError, a NaN or infinity in the state,
    or no end within :data:`HANG_LIMIT_S`; '' when none)."""
    done = refused = 0
    guard = hasattr(signal, "SIGALRM")
    previous = signal.signal(signal.SIGALRM, _hang) if guard else None
    if guard:
        signal.alarm(HANG_LIMIT_S)
    try:
        for name, sequence in frames.items():
            model = PedestrianEnvironmentModel(config)
            for frame in sequence:
                try:
                    state = model.update(frame)
                except InputError:
                    refused += 1
                    continue
                done += 1
                bad = nonfinite(state)
                if bad:
                    return done, refused, f"{name} frame {frame.index}: {bad} not finite"
    except Exception as exc:  # the property: nothing but InputError
        return done, refused, f"{type(exc).__name__}: {exc}"
    finally:
        if guard:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, previous)
    return done, refused, ""
