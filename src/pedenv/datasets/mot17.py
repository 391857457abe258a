"""MOTChallenge MOT17 files: ``seqinfo.ini``, ``gt/gt.txt`` and ``gt/gt_all_classes.txt``.

Boxes are amodal (they cover occluded parts and may extend past the image); they are
returned as ``[x_min, y_min, x_max, y_max]`` pixels, unclipped; :meth:`MotBoxes.clipped`
gives the visible extent. Frame numbers are 1-based, as in the files.
"""

from __future__ import annotations

import configparser
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.datasets.text_fields import RowTable, numbers, read_lines
from pedenv.errors import InputError

#: MOT17 classes (column 8 of the ground truth).
CLASSES = {1: "Pedestrian", 2: "Person on vehicle", 3: "Car", 4: "Bicycle", 5: "Motorbike",
           6: "Non-motorized vehicle", 7: "Static person", 8: "Distractor", 9: "Occluder",
           10: "Occluder on the ground", 11: "Occluder full", 12: "Reflection"}
PEDESTRIAN = 1
#: Classes whose matching detections are not false positives (MOTChallenge evaluation).
IGNORE_CLASSES = (2, 7, 8, 12)


@dataclass(frozen=True)
class SeqInfo:
    """The ``[Sequence]`` section of ``seqinfo.ini``.

    seq_length is the length of the full sequence, not the number of images present.
    """

    name: str
    im_dir: str
    frame_rate: float
    seq_length: int
    width: int
    height: int
    im_ext: str


def read_seqinfo(path: str | Path) -> SeqInfo:
    """Read ``seqinfo.ini``; a missing or bad key raises InputError naming it."""
    path = Path(path)
    parser = configparser.ConfigParser()
    try:
        with open(path, encoding="utf-8") as f:
            parser.read_file(f)
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except (OSError, configparser.Error) as exc:
        raise InputError(f"{path}: not a readable seqinfo.ini: {exc}") from None
    if "Sequence" not in parser:
        raise InputError(f"{path}: no [Sequence] section")
    section = parser["Sequence"]

    def get(key: str, kind: type) -> Any:
        if key not in section:
            raise InputError(f"{path}: [Sequence] lacks {key}")
        try:
            value = kind(section[key])
        except ValueError:
            raise InputError(f"{path}: [Sequence] {key} must be {kind.__name__}, got {section[key]!r}") from None
        if kind is not str and value <= 0:
            raise InputError(f"{path}: [Sequence] {key} must be > 0, got {value}")
        return value

    return SeqInfo(get("name", str), get("imDir", str), get("frameRate", float), get("seqLength", int),
                   get("imWidth", int), get("imHeight", int), get("imExt", str))


@dataclass(frozen=True)
class MotBoxes(RowTable):
    """MOT ground-truth rows (N).

    frame: (N,) int64, 1-based. ids: (N,) int64. boxes: (N, 4) float, amodal
    ``[x_min, y_min, x_max, y_max]`` pixels. consider: (N,) bool (the ``conf`` flag).
    classes: (N,) int64 (see :data:`CLASSES`). visibility: (N,) float in [0, 1].
    """

    frame: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    consider: np.ndarray
    classes: np.ndarray
    visibility: np.ndarray

    def of_class(self, *classes: int) -> MotBoxes:
        """The rows whose class is one of ``classes``."""
        return self.take(np.isin(self.classes, classes))

    def clipped(self, width: int, height: int) -> np.ndarray:
        """(N, 4) boxes clipped to an image of ``width`` x ``height`` pixels (the visible extent)."""
        return np.clip(self.boxes, 0.0, [width, height, width, height])


def read_gt(path: str | Path) -> MotBoxes:
    """Read a MOT ``gt.txt``.

    9 comma-separated columns: frame, id, left, top, width, height, conf, class, visibility.
    """
    path = Path(path)
    rows = []
    for line, text in read_lines(path):
        fields = [f.strip() for f in text.split(",")]
        if len(fields) != 9:
            raise InputError(f"{path}:{line}: a MOT17 ground-truth row has 9 columns, got {len(fields)}")
        values = numbers(path, line, fields, "ground-truth columns")
        if values[0] < 1 or values[0] != int(values[0]):
            raise InputError(f"{path}:{line}: frame must be an integer >= 1, got {fields[0]!r}")
        if values[4] < 0 or values[5] < 0:
            raise InputError(f"{path}:{line}: box width and height must be >= 0, got {fields[4]}, {fields[5]}")
        if int(values[7]) not in CLASSES:
            raise InputError(f"{path}:{line}: class must be 1..12, got {fields[7]!r}")
        if not 0.0 <= values[8] <= 1.0:
            raise InputError(f"{path}:{line}: visibility must be in [0, 1], got {fields[8]!r}")
        rows.append(values)
    t = np.array(rows, dtype=np.float64).reshape(-1, 9)
    boxes = np.stack([t[:, 2], t[:, 3], t[:, 2] + t[:, 4], t[:, 3] + t[:, 5]], axis=1)
    return MotBoxes(t[:, 0].astype(np.int64), t[:, 1].astype(np.int64), boxes, t[:, 6] != 0,
                    t[:, 7].astype(np.int64), t[:, 8])


@dataclass(frozen=True)
class Mot17Sequence:
    """One MOT17 sequence folder: its info, pedestrian ground truth, all-class rows, frames present.

    pedestrians: class-1 rows (``gt/gt.txt``). all_classes: every row (``gt/gt_all_classes.txt``,
    or ``gt.txt`` again where that file is absent). frames: 1-based numbers of the images present.
    """

    folder: Path
    info: SeqInfo
    pedestrians: MotBoxes
    all_classes: MotBoxes
    frames: tuple[int, ...]

    def image_path(self, frame: int) -> Path:
        """Path of the image of a (1-based) frame."""
        return self.folder / self.info.im_dir / f"{frame:06d}{self.info.im_ext}"

    def ignore_boxes(self, frame: int) -> np.ndarray:
        """(K, 4) amodal boxes of the ignore classes (2, 7, 8, 12) in ``frame``."""
        return self.all_classes.in_frame(frame).of_class(*IGNORE_CLASSES).boxes


def read_sequence(folder: str | Path) -> Mot17Sequence:
    """Read a MOT17 sequence folder (``seqinfo.ini``, ``gt/``, the image folder)."""
    folder = Path(folder)
    info = read_seqinfo(folder / "seqinfo.ini")
    gt = read_gt(folder / "gt" / "gt.txt")
    all_path = folder / "gt" / "gt_all_classes.txt"
    all_classes = read_gt(all_path) if all_path.is_file() else gt
    image_dir = folder / info.im_dir
    if not image_dir.is_dir():
        raise InputError(f"{image_dir}: image folder named in {folder / 'seqinfo.ini'} not found")
    frames = []
    for p in sorted(image_dir.glob(f"*{info.im_ext}")):
        if not p.stem.isdigit() or int(p.stem) < 1:
            raise InputError(f"{p}: MOT17 image names are the 1-based frame number (000001{info.im_ext})")
        frames.append(int(p.stem))
    return Mot17Sequence(folder, info, gt.of_class(PEDESTRIAN), all_classes, tuple(frames))


def sequence_folders(root: str | Path) -> list[Path]:
    """The sequence folders (those holding a ``seqinfo.ini``) directly under ``root``, sorted."""
    root = Path(root)
    return sorted(p.parent for p in root.glob("*/seqinfo.ini"))
