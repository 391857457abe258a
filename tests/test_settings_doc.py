"""docs/settings.md lists every saved setting: each field of each section of ``Config`` (nested
sections such as ``detection.stream`` field by field) appears there as ``section.field``."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pedenv  # noqa: F401  (the package registers every section of the config)
from pedenv.config import SECTIONS

DOC = Path(__file__).resolve().parents[1] / "docs" / "settings.md"


def _paths(prefix: str, kind: type) -> list[str]:
    out = []
    for field in dataclasses.fields(kind):
        default = field.default
        if dataclasses.is_dataclass(default) and not isinstance(default, type):
            out += _paths(f"{prefix}.{field.name}", type(default))
        else:
            out.append(f"{prefix}.{field.name}")
    return out


def test_every_saved_setting_is_in_the_settings_doc():
    text = DOC.read_text()
    paths = [p for name, kind in SECTIONS.items() for p in _paths(name, kind)]
    missing = [p for p in paths if f"`{p}`" not in text]
    assert not missing, f"{len(missing)} of {len(paths)} settings not in docs/settings.md: {missing[:10]}"
    assert len(paths) > 40  # the sections were found


def test_the_settings_doc_names_no_setting_that_is_gone():
    """A documented ``section.field`` of the model's sections is a field today."""
    import re

    text = DOC.read_text()
    fields = {name: {f.name for f in dataclasses.fields(kind)} for name, kind in SECTIONS.items()}
    named = re.findall(r"`(tracking|kalman|paper|fused|behaviour)\.([a-z_]+)`", text)
    gone = sorted({f"{s}.{f}" for s, f in named if f not in fields[s]})
    assert not gone, gone
