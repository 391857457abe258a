"""Manifests: many recordings in one file, one row per recording (``pedenv run --manifest``).

CSV with a header row, or YAML (a list of mappings, or a mapping with the list under
``recordings``). Fields of a row (paths relative to the manifest's folder)::

    name,images,video,calibration,ego_poses,fps,start_time
    drive-1,drive-1/images,,calib.yaml,drive-1/poses.csv,,
    drive-2,,drive-2.mp4,calib.yaml,drive-2/poses.csv,30,

* ``calibration``, ``ego_poses``: required files (formats of :mod:`pedenv.recordings.footage`);
* exactly one of ``images`` (a folder) and ``video`` (a file);
* ``name`` (optional): the recording's output folder, by default the image folder's name or
  the video's stem; names must be distinct, usable as a folder name (at most 255 bytes) and
  none of the names the run itself writes in the output folder (:data:`RESERVED_NAMES`);
* ``fps``, ``start_time`` (optional, seconds): as ``pedenv run --fps/--start-time``.

Every problem is one :class:`~pedenv.errors.InputError` naming the manifest, the row
(1 = the first recording) and the field.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass
from pathlib import Path

from pedenv.errors import InputError
from pedenv.paths import MARKER, MAX_NAME_BYTES, check_path
from pedenv.structured_text import parse_yaml, read_limited_text

FIELDS = ("name", "images", "video", "calibration", "ego_poses", "fps", "start_time")
#: The manifest run's summary file in the output folder.
SUMMARY = "summary.json"
#: Names no recording may take: the files the manifest run writes beside the recordings' folders.
RESERVED_NAMES = (SUMMARY, MARKER)


@dataclass(frozen=True)
class ManifestRow:
    """One recording of a manifest: absolute paths, optional frame timing; ``row`` counts from 1."""

    name: str
    calibration: Path
    ego_poses: Path
    images: Path | None = None
    video: Path | None = None
    fps: float | None = None
    start_time: float | None = None
    row: int = 0


def read_manifest(path: str | Path) -> list[ManifestRow]:
    """The recordings of a CSV (``.csv``) or YAML (``.yaml``/``.yml``) manifest, checked (see the module doc)."""
    path = Path(path)
    text = read_limited_text(path, "the manifest")
    if path.suffix.lower() == ".csv":
        raw = _csv_rows(path, text)
    elif path.suffix.lower() in (".yaml", ".yml"):
        raw = _yaml_rows(path, text)
    else:
        raise InputError(f"{path}: a manifest must be a .csv or .yaml file")
    if not raw:
        raise InputError(f"{path}: the manifest lists no recording")
    rows = [_row(path, n, fields) for n, fields in enumerate(raw, start=1)]
    seen: dict[str, int] = {}
    for r in rows:
        if r.name in seen:
            raise InputError(f"{path}: row {r.row}: name {r.name!r} is also row {seen[r.name]}'s; every recording "
                             f"needs its own name (its output folder)")
        seen[r.name] = r.row
    return rows


def _csv_rows(path: Path, text: str) -> list[dict]:
    try:
        reader = csv.DictReader(io.StringIO(text))
        header = [h.strip() for h in reader.fieldnames or []]
        rows = [row for row in reader if any((v or "").strip() for v in row.values() if isinstance(v, str))]
    except csv.Error as exc:
        raise InputError(f"{path}: not a valid CSV file: {exc}") from None
    _check_fields(path, "header", header)
    for n, row in enumerate(rows, start=1):
        if None in row:
            raise InputError(f"{path}: row {n} has more cells than the header's {len(header)} fields")
    return [{k.strip(): (v or "").strip() for k, v in row.items()} for row in rows]


def _yaml_rows(path: Path, text: str) -> list[dict]:
    data = parse_yaml(text, path, "the manifest")  # nesting and alias limits
    if isinstance(data, dict) and "recordings" in data:
        data = data["recordings"]
    if not isinstance(data, list) or not all(isinstance(r, dict) for r in data):
        raise InputError(f"{path}: a YAML manifest must be a list of recordings (mappings), or hold one under "
                         f"'recordings'")
    for n, row in enumerate(data, start=1):
        _check_fields(path, f"row {n}", [str(k) for k in row])
    return [{str(k): "" if v is None else v for k, v in row.items()} for row in data]


def _check_fields(path: Path, where: str, names: list[str]) -> None:
    unknown = [n for n in names if n not in FIELDS]
    if unknown:
        raise InputError(f"{path}: {where}: unknown field(s) {', '.join(map(repr, unknown))}; fields: "
                         f"{', '.join(FIELDS)}")


def _row(manifest: Path, n: int, fields: dict) -> ManifestRow:
    where = f"{manifest}: row {n}"
    images = _file_field(manifest, where, fields, "images", "folder", required=False)
    video = _file_field(manifest, where, fields, "video", "file", required=False)
    if (images is None) == (video is None):
        raise InputError(f"{where}: give exactly one of the fields 'images' (a folder) and 'video' (a file)")
    calibration = _file_field(manifest, where, fields, "calibration", "file", required=True)
    ego_poses = _file_field(manifest, where, fields, "ego_poses", "file", required=True)
    assert calibration is not None and ego_poses is not None  # required above
    name = str(fields.get("name") or "").strip() or _default_name(images, video)
    if "/" in name or "\\" in name or name in (".", "..") or len(os.fsencode(name)) > MAX_NAME_BYTES:
        raise InputError(f"{where}: field 'name' must be usable as a folder name (no / or \\, at most "
                         f"{MAX_NAME_BYTES} bytes), got {_short(name)!r}")
    if name in RESERVED_NAMES:
        raise InputError(f"{where}: field 'name' {name!r} is the name of a file the run writes in the output folder "
                         f"({', '.join(RESERVED_NAMES)}); choose another name")
    return ManifestRow(name, calibration, ego_poses, images, video, _number_field(where, fields, "fps", positive=True),
                       _number_field(where, fields, "start_time", positive=False), row=n)


def _file_field(manifest: Path, where: str, fields: dict, key: str, kind: str, *, required: bool) -> Path | None:
    """The existing ``kind`` ("folder" or "file") that field ``key`` names, relative to the manifest's
    folder; None for an empty field unless ``required``."""
    value = fields.get(key, "")
    if value in ("", None):
        if required:
            raise InputError(f"{where}: field {key!r} is missing")
        return None
    p = check_path(Path(str(value)).expanduser(), f"{where}: field {key!r}:")
    p = p if p.is_absolute() else manifest.parent / p
    exists = p.is_dir() if kind == "folder" else p.is_file()
    if not exists:
        raise InputError(f"{where}: field {key!r}: {kind} {p} not found")
    return p


def _number_field(where: str, fields: dict, key: str, *, positive: bool) -> float | None:
    """Field ``key`` as a finite number (above 0 when ``positive``), or None when it is empty."""
    value = fields.get(key, "")
    if value in ("", None):
        return None
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{where}: field {key!r} must be a number, got {value!r}") from None
    if not math.isfinite(x) or (positive and x <= 0):
        bound = " > 0" if positive else ""
        raise InputError(f"{where}: field {key!r} must be a finite number{bound}, got {value!r}")
    return x


def _default_name(images: Path | None, video: Path | None) -> str:
    """A recording's name when its row gives none: the image folder's name, else the video's stem."""
    if images is not None:
        return images.resolve().name
    assert video is not None  # a row holds exactly one of the two (checked before)
    return video.stem


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else f"{text[:limit // 2]}...{text[-limit // 3:]}"
