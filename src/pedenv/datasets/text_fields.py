"""Shared helpers for the real-data readers: numbered lines, numeric fields, clear errors."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any, ClassVar, Self

import numpy as np

from pedenv.errors import InputError


def read_lines(path: str | Path) -> Iterator[tuple[int, str]]:
    """``(line number from 1, stripped text)`` of every non-empty line of ``path``."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if line:
            yield number, line


def numbers(path: Path, line: int, fields: list[str], what: str) -> np.ndarray:
    """The ``fields`` as float64 (finite); an unparsable one raises InputError naming file and line."""
    try:
        values = np.array([float(f) for f in fields], dtype=np.float64)
    except ValueError:
        raise InputError(f"{path}:{line}: {what} must be numbers, got {' '.join(fields)!r}") from None
    if not np.all(np.isfinite(values)):
        raise InputError(f"{path}:{line}: {what} contains NaN or inf")
    return values


def frozen_arrays(obj: object, **arrays: np.ndarray) -> None:
    """Set read-only array fields on a frozen dataclass instance."""
    for name, value in arrays.items():
        value = np.asarray(value)
        value.setflags(write=False)
        object.__setattr__(obj, name, value)


class RowTable:
    """Base of a frozen dataclass of arrays with one row per record (every field N rows, N the
    first field's): on construction the lengths are checked (InputError naming the field) and
    the arrays made read-only; ``len`` is N, :meth:`take` selects rows, :meth:`in_frame` the
    rows of one frame (the ``frame`` field)."""

    __dataclass_fields__: ClassVar[dict[str, Any]]
    frame: np.ndarray

    def __post_init__(self) -> None:
        arrays: dict[str, Any] = {name: getattr(self, name) for name in self.__dataclass_fields__}
        n = len(next(iter(arrays.values())))
        for name, value in arrays.items():
            if len(value) != n:
                raise InputError(f"{type(self).__name__}.{name} must have {n} rows, got {len(value)}")
        frozen_arrays(self, **arrays)

    def __len__(self) -> int:
        return len(self.frame)

    def take(self, mask: np.ndarray) -> Self:
        """The rows selected by a boolean mask or index array."""
        return type(self)(**{name: getattr(self, name)[mask] for name in self.__dataclass_fields__})

    def in_frame(self, frame: int) -> Self:
        """The rows of one frame (numbered as the dataset numbers them)."""
        return self.take(self.frame == frame)
