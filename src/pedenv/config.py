"""One typed configuration object; every constant of the paper is a named, validated value.

Defaults are the paper's (Holzbock et al., Sections III-B and III-C) where it gives one.
``Config.to_dict()`` is saved next to every result (``config.json``) so a run can be
repeated: the tracker, the position methods, the behaviour cues, and the sections of the
stages above the core that register theirs (:func:`register_section`: the detection stage's
``redetect`` and ``detection``, from :mod:`pedenv.detection.config`, which
``import pedenv`` loads). The core imports nothing of those stages. Every section checks its fields with
:mod:`pedenv.validation` (type, finiteness, a range with a documented upper bound) and
raises :class:`~pedenv.errors.InputError` naming ``section.field``; ``Config.load`` reads
the file through :mod:`pedenv.structured_text` (size and nesting limits) and names it.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pedenv.behaviour.config import BehaviourConfig
from pedenv.config_position import FUSED_CUES, INITIAL_ESTIMATES, FusedConfig, PaperConfig
from pedenv.config_tracking import KalmanConfig, TrackingConfig
from pedenv.errors import InputError
from pedenv.structured_text import load_json
from pedenv.validation import shown

__all__ = ["DEFAULT_METHOD", "FUSED_CUES", "INITIAL_ESTIMATES", "METHOD_PRESETS", "SECTIONS", "Config",
           "BehaviourConfig", "FusedConfig", "KalmanConfig", "PaperConfig", "TrackingConfig", "register_section"]

#: The position method of ``Config()`` and of every command without ``--method``: the
#: most accurate one (``paper`` reproduces the paper's figures).
DEFAULT_METHOD = "fused"

#: Per method, the fields whose defaults differ from the section classes' own defaults
#: (which are the paper's values). ``fused`` turns on the tracker's height-ratio rule,
#: low-score second pass, motion prediction, ground gate and track memory, and the
#: filter's restart gate, the re-detection of missed tracks in crops (onnx backend,
#: :mod:`pedenv.detection.redetect`) and the behaviour cues (:mod:`pedenv.behaviour`) (on the golden
#: ``terrain2/fused/detector-model`` case 75 identity
#: switches with them, 200 without).
METHOD_PRESETS: dict[str, dict[str, dict]] = {
    "paper": {},
    "fused": {"tracking": {"max_height_ratio": 1.5, "predict_motion": True, "low_score_threshold": 0.1,
                           "ground_gate": 4.0, "memory_s": 2.0},
              "kalman": {"restart_gate": 25.0}, "redetect": {"enabled": True}, "behaviour": {"enabled": True}},
}


@dataclass(frozen=True)
class Config:
    """Everything the environment model needs besides the data.

    method: the position method, a name of :data:`pedenv.localization.LOCATORS`:
        ``fused`` (the default, the best one) or ``paper`` (reproduces the paper); another
        name is refused here, naming the valid ones. Each method's constants are in its own section.

    A section not given starts from the method's defaults (:data:`METHOD_PRESETS` over the
    section class's defaults), so ``Config()`` is the fused method as every command runs it
    and ``Config(method="paper")`` the paper's. ``pedenv.localization.configure`` switches
    a config to another method. A saved config without ``method`` (as written before the
    field existed) loads as ``fused``; the fields it names keep their values.

    behaviour: the behaviour cues (:class:`pedenv.behaviour.config.BehaviourConfig`; on in ``fused``).
    redetect, detection: the detection stage's sections (``onnx`` backend,
    :mod:`pedenv.detection.config`, registered by it), saved with the run so its detection is
    recorded; ``pedenv run --detection`` sets ``detection.mode``. A saved config without them
    (written before they were) loads their defaults; one with settings that are no longer
    settings loads when they hold today's fixed values (:func:`drop_retired`; the ``merge``
    section is such a one).
    """

    method: str = DEFAULT_METHOD
    # None (the default): the method's defaults, filled in by __post_init__
    tracking: TrackingConfig = None  # type: ignore[assignment]
    paper: PaperConfig = None  # type: ignore[assignment]
    kalman: KalmanConfig = None  # type: ignore[assignment]
    fused: FusedConfig = None  # type: ignore[assignment]
    redetect: Any = None  # the detection stage's sections (register_section): pedenv.detection.config
    detection: Any = None
    behaviour: BehaviourConfig = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if not isinstance(self.method, str) or not self.method or len(self.method) > 64:
            raise InputError(f"method must be the name of a position method, got {shown(self.method)}")
        if self.method not in METHOD_PRESETS:
            raise InputError(f"unknown position method {shown(self.method)}; valid: {', '.join(METHOD_PRESETS)}")
        missing = [name for name in STAGE_SECTIONS if name not in SECTIONS]
        if missing:
            raise InputError(f"config section(s) {', '.join(missing)} not registered: import pedenv first")
        preset = METHOD_PRESETS.get(self.method, {})
        for name, kind in SECTIONS.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, kind(**preset.get(name, {})))

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Config:
        """The config of ``data`` (a dict as :meth:`to_dict` gives or ``config.json`` holds);
        lists stand for the tuple fields (``fused.cues``, ``detection.level_scales``)."""
        if not isinstance(data, dict):
            raise InputError(f"a config must be an object of sections, got {type(data).__name__}")
        for name in sorted(set(data) & set(RETIRED_SECTIONS)):  # a section that is no longer saved
            values = data[name]
            if not isinstance(values, dict):
                raise InputError(f"config.{name} must be an object of fields, got {type(values).__name__}")
            extra = set(values) - set(RETIRED_SECTIONS[name])
            if extra:
                raise InputError(f"unknown field(s) in config.{name}: {_names(extra)}")
            drop_retired(name, values, RETIRED_SECTIONS[name])
        data = {k: v for k, v in data.items() if k not in RETIRED_SECTIONS}
        unknown = set(data) - set(SECTIONS) - {"method"}
        if unknown:
            raise InputError(f"unknown config section(s): {_names(unknown)}; valid: method, {', '.join(SECTIONS)}")
        method = data.get("method", DEFAULT_METHOD)
        preset = METHOD_PRESETS.get(method, {}) if isinstance(method, str) else {}
        built = {}
        for name, kind in SECTIONS.items():
            values = data.get(name, {})
            if not isinstance(values, dict):
                raise InputError(f"config.{name} must be an object of fields, got {type(values).__name__}")
            values = drop_retired(name, values, RETIRED_FIELDS.get(name, {}))
            names = {f.name for f in dataclasses.fields(kind)}
            extra = set(values) - names
            if extra:
                raise InputError(f"unknown field(s) in config.{name}: {_names(extra)}; "
                                 f"valid: {', '.join(sorted(names))}")
            values = {k: tuple(v) if isinstance(v, list) else v for k, v in values.items()}
            built[name] = kind(**{**preset.get(name, {}), **values})
        return cls(method=method, **built)

    def replace(self, method: str | None = None, **sections: dict[str, Any]) -> Config:
        """A copy with the method or some sections' fields changed:
        ``cfg.replace(paper={"refine": False})``. A new ``method`` here keeps every section
        as it is; :func:`pedenv.localization.configure` switches to a method with its defaults."""
        data = self.to_dict()
        if method is not None:
            data["method"] = method
        for name, values in sections.items():
            if name not in SECTIONS:
                raise InputError(f"unknown config section {name!r}; valid: {', '.join(SECTIONS)}")
            data[name] = {**data[name], **values}
        return Config.from_dict(data)

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> Config:
        """The config saved at ``path`` (JSON); every error names the file."""
        path = Path(path)
        data = load_json(path, "the config")
        if not isinstance(data, dict):
            raise InputError(f"{path}: a config must be a JSON object of sections, got {type(data).__name__}")
        try:
            return cls.from_dict(data)
        except InputError as exc:
            raise InputError(f"{path}: {exc}") from None


def _names(names: Iterable[object]) -> str:
    """Unknown names of a config, sorted and shortened (a hostile file may hold thousands)."""
    listed = sorted(str(n)[:40] for n in names)
    return ", ".join(listed[:5]) + (f" and {len(listed) - 5} more" if len(listed) > 5 else "")


#: Section name -> its class, in the order ``config.json`` lists them: the core's, then those the
#: stages above it register (:func:`register_section`).
SECTIONS: dict[str, type] = {"tracking": TrackingConfig, "paper": PaperConfig, "kalman": KalmanConfig,
                             "fused": FusedConfig, "behaviour": BehaviourConfig}
#: The sections a :class:`Config` has that a stage above the core registers.
STAGE_SECTIONS = ("redetect", "detection")


#: Per section, fields that are no longer settings and their fixed values (:func:`drop_retired`).
RETIRED_FIELDS: dict[str, Mapping[str, object]] = {
    name: getattr(kind, "RETIRED", {}) for name, kind in SECTIONS.items() if getattr(kind, "RETIRED", None)}
#: Whole sections that are no longer settings, with their fields' fixed values.
RETIRED_SECTIONS: dict[str, Mapping[str, object]] = {}


def register_section(name: str, kind: type, retired: Mapping[str, object] | None = None) -> None:
    """Make ``kind`` (a frozen dataclass of validated fields) the class of section ``name``
    (one of :data:`STAGE_SECTIONS`), saved in ``config.json`` and loaded from it; ``retired``: its
    fields that are no longer settings and their fixed values. Called by
    :mod:`pedenv.detection.config` when it is imported (``import pedenv`` does)."""
    if name not in STAGE_SECTIONS:
        raise ValueError(f"unknown stage section {name!r}; valid: {', '.join(STAGE_SECTIONS)}")
    SECTIONS[name] = kind
    RETIRED_FIELDS[name] = dict(retired or {})


def retire_section(name: str, retired: Mapping[str, object]) -> None:
    """Section ``name`` is no longer saved; a ``config.json`` holding it at the fixed values ``retired`` still loads."""
    RETIRED_SECTIONS[name] = dict(retired)


def drop_retired(where: str, values: dict, retired: Mapping[str, object]) -> dict:
    """``values`` (a section of a saved config, named ``where``) without the fields that are no
    longer settings; such a field holding another value than its fixed one is refused, named."""
    for field, fixed in retired.items():
        if field in values:
            given = values[field]
            if isinstance(given, bool) or isinstance(fixed, bool):
                same = given is fixed
            elif isinstance(fixed, tuple):
                same = isinstance(given, list | tuple) and tuple(given) == fixed
            else:
                same = isinstance(given, int | float) and given == fixed
            if not same:
                raise InputError(f"{where}.{field} is no longer a setting (fixed at {fixed!r}); remove it from "
                                 f"the config, got {shown(given)}")
    return {k: v for k, v in values.items() if k not in retired}
