"""The environment model as JSON Lines: one line per frame, flushed as it is written.

Each line is ``EnvironmentState.to_dict()``: scene, frame, timestamp, ego pose and the
pedestrians with track id, position, velocity, covariance, 2D and 3D skeleton. A run
that stops at a bad frame leaves every line written before it on disk.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import BinaryIO

from pedenv.errors import InputError
from pedenv.paths import writable_file
from pedenv.state import EnvironmentState


class EnvironmentWriter:
    """Context manager appending states to ``path`` (created with its folder); ``lines`` counts them.

    Each line is written whole or not at all: a write that fails (a full disk) cuts the file back
    to the end of the line before and raises one InputError naming the file.
    """

    def __init__(self, path: str | Path, decimals: int = 3) -> None:
        self.path = Path(path)
        self.decimals = decimals
        self.lines = 0
        self._file: BinaryIO | None = None
        self._size = 0

    def __enter__(self) -> EnvironmentWriter:
        path = writable_file(self.path, "environment model")
        try:
            self._file = path.open("wb", buffering=0)
        except OSError as exc:
            raise InputError(f"environment model {path} cannot be written: {exc.strerror or exc}") from None
        return self

    def write(self, state: EnvironmentState) -> None:
        self.write_line(environment_line(state, self.decimals))

    def write_line(self, line: str) -> None:
        """Append one line made by :func:`environment_line` (a state computed elsewhere, e.g. on a Ray worker)."""
        if self._file is None:
            raise InputError(f"{self.path}: EnvironmentWriter.write() outside its with block")
        data = memoryview((line + "\n").encode())
        try:
            done = 0
            while done < len(data):
                done += self._file.write(data[done:]) or 0
        except OSError as exc:
            self._file.truncate(self._size)  # the cut line removed: every line is whole
            raise InputError(f"{self.path}: cannot be written: {exc.strerror or exc}") from None
        self._size += len(data)
        self.lines += 1

    def __exit__(self, *exc: object) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def environment_line(state: EnvironmentState, decimals: int = 3) -> str:
    """One line of the environment model (no newline): ``state.to_dict(decimals)`` as compact JSON."""
    return json.dumps(state.to_dict(decimals), separators=(",", ":"), allow_nan=False)


def read_environment(path: str | Path) -> list[dict]:
    """The lines of a JSON Lines environment model as dicts."""
    with Path(path).open() as f:
        return [json.loads(line) for line in f if line.strip()]
