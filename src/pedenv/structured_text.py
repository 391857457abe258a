"""YAML and JSON a user hands to pedenv, read with limits on size, nesting and alias expansion.

Every YAML or JSON file pedenv reads from a user (the config, the calibration, the manifest)
goes through :func:`load_yaml` / :func:`load_json` (or :func:`parse_yaml` / :func:`parse_json`
for text already read). A few bytes must not cost gigabytes or a 3,000-line traceback:

- a file larger than :data:`MAX_BYTES` is refused before it is read;
- YAML is first walked as a stream of parser events (no objects built, no recursion): a
  document nested deeper than :data:`MAX_DEPTH` or whose aliases expand to more than
  :data:`MAX_VALUES` values (a 610-byte file of 9 levels of 9 aliases expands to 387
  million) is refused before PyYAML's recursive composer builds it;
- JSON nested deeper than :data:`MAX_DEPTH` is refused (Python's decoder recurses; a
  ``RecursionError`` it raises becomes the same one line).

Every error is one :class:`~pedenv.errors.InputError` naming the file and never holding the
document's values.
"""

from __future__ import annotations

import json
import os
import stat
from pathlib import Path
from typing import Any

import yaml

from pedenv.errors import InputError

#: Largest YAML or JSON file read, bytes (10 MB; a manifest of 10,000 recordings is about 1 MB).
MAX_BYTES = 10_000_000
#: Deepest nesting of lists and mappings (pedenv's own files nest 3 deep).
MAX_DEPTH = 64
#: Most values (scalars, lists and mappings) a YAML document may hold once its aliases are
#: expanded (a manifest of :data:`MAX_BYTES` with 20-byte values holds half of it).
MAX_VALUES = 1_000_000
#: A scalar counts as one value per this many characters, so a long string repeated by
#: aliases counts as what it costs.
SCALAR_CHARS = 100

_OPEN = (yaml.SequenceStartEvent, yaml.MappingStartEvent)
_CLOSE = (yaml.SequenceEndEvent, yaml.MappingEndEvent)


def _read_bytes(path: str | Path, what: str) -> bytes:
    """The bytes of ``path`` if at most :data:`MAX_BYTES`, never allocating more (a regular file
    is measured before it is read; a pipe is read in chunks until it ends or passes the limit)."""
    with open(path, "rb") as f:
        info = os.fstat(f.fileno())
        chunks: list[bytes] = []
        if stat.S_ISREG(info.st_mode) and info.st_size <= MAX_BYTES:
            chunks.append(f.read(info.st_size + 1))  # +1: a file grown since shows it
        elif not stat.S_ISREG(info.st_mode):
            while sum(map(len, chunks)) <= MAX_BYTES and (chunk := f.read(1 << 16)):
                chunks.append(chunk)
        if not stat.S_ISREG(info.st_mode) or info.st_size <= MAX_BYTES:
            data = b"".join(chunks)
            if len(data) <= MAX_BYTES:
                return data
    raise InputError(f"{path}: {what} is larger than {MAX_BYTES:,} bytes")


def read_limited_text(path: str | Path, what: str) -> str:
    """The text of ``path`` (UTF-8, a byte-order mark accepted) if it holds at most
    :data:`MAX_BYTES`; ``what`` it holds (e.g. "the config") names it in the error."""
    try:
        data = _read_bytes(path, what)
    except OSError as exc:
        raise InputError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError(f"{path}: {what} is not UTF-8 text (a binary file?)") from None


def _mark(exc: yaml.YAMLError) -> str:
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or type(exc).__name__
    return f"line {mark.line + 1}, column {mark.column + 1}: {problem}" if mark is not None else str(problem)


def _completed_node(event: yaml.Event, sizes: list[int], names: list[str | None], anchors: dict[str, int],
                    where: str) -> tuple[int, str | None] | None:
    """The expanded values and the anchor of the node ``event`` completes (a collection it closes,
    popped from ``sizes`` and ``names``; an alias; a scalar), or None for an event that completes none."""
    if isinstance(event, _CLOSE):
        return sizes.pop(), names.pop()
    if isinstance(event, yaml.AliasEvent):
        if event.anchor in names:
            raise InputError(f"{where} holds a recursive YAML alias (*{event.anchor[:40]})")
        return anchors.get(event.anchor, 1), None
    if isinstance(event, yaml.ScalarEvent):
        return 1 + len(event.value) // SCALAR_CHARS, event.anchor
    return None


def check_yaml_events(text: str, source: object, what: str) -> None:
    """Refuse a YAML text nested deeper than :data:`MAX_DEPTH` or expanding to more than
    :data:`MAX_VALUES` values, from its parser events alone (iterative, nothing built)."""
    sizes: list[int] = []  # per open collection: the expanded values inside it so far
    anchors: dict[str, int] = {}  # anchor -> the expanded values of the node it names
    names: list[str | None] = []  # per open collection: its anchor
    total = 0
    where = f"{source}: {what}"
    for event in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(event, _OPEN):
            if len(sizes) >= MAX_DEPTH:
                raise InputError(f"{where} is nested deeper than {MAX_DEPTH} levels")
            sizes.append(1)
            names.append(event.anchor)
            continue
        node = _completed_node(event, sizes, names, anchors, where)
        if node is None:
            continue
        size, anchor = node
        if anchor is not None:
            anchors[anchor] = size
        if sizes:
            sizes[-1] += size
        else:
            total += size
        if total + sum(sizes) > MAX_VALUES:
            raise InputError(f"{where} expands to more than {MAX_VALUES:,} values (YAML aliases?)")


def parse_yaml(text: str, source: object, what: str = "the file") -> Any:
    """The YAML document in ``text`` (PyYAML's safe loader: data only, never code), read from
    ``source`` (a path, named in every error), within the limits of the module doc."""
    try:
        check_yaml_events(text, source, what)
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputError(f"{source}: not valid YAML ({_mark(exc)})") from None
    except RecursionError:
        raise InputError(f"{source}: {what} is nested too deeply to read") from None


def _json_depth_ok(data: Any) -> bool:
    stack = [(data, 1)]
    while stack:
        node, depth = stack.pop()
        children = node.values() if isinstance(node, dict) else node if isinstance(node, list) else ()
        for child in children:
            if isinstance(child, (dict, list)):
                if depth + 1 > MAX_DEPTH:
                    return False
                stack.append((child, depth + 1))
    return True


def parse_json(text: str, source: object, what: str = "the file") -> Any:
    """The JSON document in ``text`` read from ``source`` (named in every error), nested at
    most :data:`MAX_DEPTH` deep. ``NaN`` and ``Infinity`` parse as floats; the field that
    gets one refuses it (:func:`pedenv.validation.check_number`)."""
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{source}: {what} is not valid JSON (line {exc.lineno}, column {exc.colno}: "
                         f"{exc.msg})") from None
    except RecursionError:
        data = None
        deep = True
    else:
        deep = not _json_depth_ok(data)
    if deep:
        raise InputError(f"{source}: {what} is nested deeper than {MAX_DEPTH} levels")
    return data


def load_yaml(path: str | Path, what: str = "the file") -> Any:
    """The YAML document in the file ``path`` (see :func:`parse_yaml`), at most :data:`MAX_BYTES`."""
    return parse_yaml(read_limited_text(path, what), path, what)


def load_json(path: str | Path, what: str = "the file") -> Any:
    """The JSON document in the file ``path`` (see :func:`parse_json`), at most :data:`MAX_BYTES`."""
    return parse_json(read_limited_text(path, what), path, what)
