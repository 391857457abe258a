"""The track table: the one owner of every per-track row.

Tracks are rows of arrays (struct of arrays), so a frame costs a handful of vectorized
operations, not a Python loop per pedestrian. The columns come in named groups: the
tracker's own (``ids``, ``boxes``, ``misses``, ``hits``, ``velocities``), the Kalman
filter's (``x``, ``P``, ``started``) and one group per position method (its memory of
past observations). When the tracker decides the next frame's table it calls
:meth:`TrackTable.carry` once, and every column of every group follows: per-track state
cannot go out of step, whoever adds it.
"""

from __future__ import annotations

import numpy as np


def carry_rows(array: np.ndarray, previous_rows: np.ndarray, fill: float = 0) -> np.ndarray:
    """Re-order per-track ``array`` (T_old, ...) to the new table; new rows get ``fill``.

    previous_rows: (T_new,) int, each new row's row in the old table or -1 for a new track.
    """
    if len(array) == 0:
        return np.full((len(previous_rows),) + array.shape[1:], fill, dtype=array.dtype)
    out = array[previous_rows]  # a new track's -1 takes the last row for now (one copy, no padding)
    new = previous_rows < 0
    if new.any():
        out[new] = fill
    return out


class ColumnGroup:
    """A named group of per-track columns, each an attribute of shape (T, ...).

    columns: column name -> ``(row shape, dtype)``; every column starts with no rows and a
    new track's row is zero (False for booleans). Subclasses declare their columns as
    annotated attributes (``boxes: np.ndarray``) so readers and type checkers see them.
    """

    def __init__(self, columns: dict[str, tuple[tuple[int, ...], type]]) -> None:
        self._columns = dict(columns)
        self.clear()

    def clear(self) -> None:
        """No rows."""
        for name, (shape, dtype) in self._columns.items():
            setattr(self, name, np.zeros((0,) + tuple(shape), dtype))

    def carry(self, previous_rows: np.ndarray) -> None:
        """Follow the new table (see :func:`carry_rows`)."""
        for name in self._columns:
            setattr(self, name, carry_rows(getattr(self, name), previous_rows))


class TrackColumns(ColumnGroup):
    """The tracker's columns: ``ids (T,)`` int64; ``boxes (T, 4)`` pixels of the latest frame
    (ego-yaw compensated); ``misses (T,)`` consecutive frames without a detection; ``hits
    (T,)`` detections so far; ``velocities (T, 4)`` pixels per frame of the box edges;
    ``lost (T,)`` bool, a track missed too often and only remembered (``tracking.memory_s``:
    it takes no part in the association in the image); ``last_seen (T,)`` seconds, the
    timestamp of its latest detection (kept only while a camera view is given)."""

    ids: np.ndarray
    boxes: np.ndarray
    misses: np.ndarray
    hits: np.ndarray
    velocities: np.ndarray
    lost: np.ndarray
    last_seen: np.ndarray

    def __init__(self) -> None:
        super().__init__({"ids": ((), np.int64), "boxes": ((4,), np.float64), "misses": ((), np.int64),
                          "hits": ((), np.int64), "velocities": ((4,), np.float64), "lost": ((), bool),
                          "last_seen": ((), np.float64)})


class FilterColumns(ColumnGroup):
    """The Kalman filter's columns: ``x (T, 4)`` state ``[x, vx, y, vy]`` (world, metres and
    m/s), ``P (T, 4, 4)`` its covariance, ``started (T,)`` the filter holds a state."""

    x: np.ndarray
    P: np.ndarray
    started: np.ndarray

    def __init__(self) -> None:
        super().__init__({"x": ((4,), np.float64), "P": ((4, 4), np.float64), "started": ((), bool)})


class TrackTable:
    """Every per-track row: ``tracks`` (the tracker's), ``filter`` (the Kalman filter's)
    and ``locator`` (the position method's memory; an empty group if it keeps none)."""

    def __init__(self, locator: ColumnGroup | None = None) -> None:
        self.tracks = TrackColumns()
        self.filter = FilterColumns()
        self.locator = locator if locator is not None else ColumnGroup({})

    @property
    def groups(self) -> tuple[ColumnGroup, ...]:
        return (self.tracks, self.filter, self.locator)

    def __len__(self) -> int:
        return len(self.tracks.ids)

    def clear(self) -> None:
        """No tracks (a new scene)."""
        for group in self.groups:
            group.clear()

    def carry(self, previous_rows: np.ndarray) -> None:
        """Re-order every column of every group to the next frame's table.

        previous_rows: (T_new,) each new row's row in the current table, -1 for a new track.
        """
        for group in self.groups:
            group.carry(previous_rows)
