"""The ego vehicle's poses of a user's recording: a CSV file -> a time-stamped trajectory.

Ego poses (CSV, vehicle -> world, timestamps in seconds, rows sorted by time), either
``timestamp,x,y,z,qw,qx,qy,qz`` or ``timestamp,x,y,yaw`` (yaw in radians, z = 0).
Each frame gets the pose interpolated at its timestamp (linear position, slerp rotation).
Positions must lie within :data:`MAX_EGO_COORDINATE_M` of the world origin.
"""

from __future__ import annotations

import csv
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from pedenv.errors import InputError, check_array
from pedenv.records import EgoPose

#: Farthest ego position from the world origin, metres, in x, y and z (10,000 km: UTM
#: eastings and northings fit). Beyond it float64 positions lose the millimetres the model
#: needs (at 1e20 m two adjacent floats are 16 km apart).
MAX_EGO_COORDINATE_M = 1e7
#: Largest timestamp in seconds (about 3,000 years of Unix time); beyond it float64 steps exceed 0.1 ms.
MAX_TIMESTAMP_S = 1e11
POSE_HEADERS = (("timestamp", "x", "y", "z", "qw", "qx", "qy", "qz"), ("timestamp", "x", "y", "yaw"))


def slerp(q0: np.ndarray, q1: np.ndarray, fraction: float) -> np.ndarray:
    """Spherical interpolation between unit quaternions ``[w, x, y, z]`` (shortest arc).

    Returns the rotation ``fraction`` (0..1) of the way from ``q0`` to ``q1`` as a unit
    quaternion ``[w, x, y, z]`` with ``w >= 0`` (scipy's :class:`~scipy.spatial.transform.Slerp`).
    """
    ends = Rotation.from_quat(np.stack([q0, q1]), scalar_first=True)
    return Slerp([0.0, 1.0], ends)(fraction).as_quat(canonical=True, scalar_first=True)


@dataclass(frozen=True)
class EgoTrajectory:
    """Time-stamped ego poses of a recording.

    timestamps: (T,) seconds, strictly increasing. translations: (T, 3) world frame, metres.
    quaternions: (T, 4) unit ``[w, x, y, z]``, vehicle -> world. source: the file they came from.
    """

    timestamps: np.ndarray
    translations: np.ndarray
    quaternions: np.ndarray
    source: str = ""
    _rotations: Slerp | Rotation = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        ts = check_array("ego timestamps", self.timestamps, (None,))
        if len(ts) == 0 or np.any(np.diff(ts) <= 0):
            raise InputError(f"{self.source or 'ego poses'}: timestamps must be non-empty and strictly increasing")
        object.__setattr__(self, "timestamps", ts)
        object.__setattr__(self, "translations", check_array("ego translations", self.translations, (len(ts), 3)))
        object.__setattr__(self, "quaternions", check_array("ego quaternions", self.quaternions, (len(ts), 4)))
        # one interpolator for the whole trajectory, built once (not two rotations per frame)
        rotations = Rotation.from_quat(self.quaternions, scalar_first=True)
        object.__setattr__(self, "_rotations", Slerp(ts, rotations) if len(ts) > 1 else rotations[0])

    def at(self, timestamp: float) -> EgoPose | None:
        """The pose interpolated at ``timestamp`` seconds; None outside the recorded span."""
        ts = self.timestamps
        if not ts[0] <= timestamp <= ts[-1]:
            return None
        if len(ts) == 1:
            return EgoPose(self.translations[0], self._rotations.as_matrix())
        i = int(np.clip(np.searchsorted(ts, timestamp, side="right") - 1, 0, len(ts) - 2))
        f = (timestamp - ts[i]) / (ts[i + 1] - ts[i])
        pos = (1.0 - f) * self.translations[i] + f * self.translations[i + 1]
        return EgoPose(pos, self._rotations(timestamp).as_matrix())


def load_ego_poses(path: str | Path) -> EgoTrajectory:
    """The ego poses of a CSV file (format in the module doc); rows must be sorted by time."""
    path = Path(path)
    rows = _read_rows(path)
    header = tuple(c.strip().lower() for c in rows[0]) if rows else ()
    if header not in POSE_HEADERS:
        raise InputError(f"{path}: ego poses header must be {' or '.join(','.join(h) for h in POSE_HEADERS)}, "
                         f"got {','.join(header) or 'an empty file'}")
    if len(rows) < 2:
        raise InputError(f"{path}: no ego pose rows after the header")
    values = _row_values(path, header, rows[1:])
    ts = values[:, 0]
    trans, quats = _translations_quaternions(path, header, values)
    _warn_implausible_speed(path, ts, trans)
    return EgoTrajectory(ts, trans, quats, str(path))


def _read_rows(path: Path) -> list[list[str]]:
    """The CSV rows of ``path`` that hold something (a byte-order mark is accepted)."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            return [r for r in csv.reader(f) if any(c.strip() for c in r)]
    except OSError as exc:
        raise InputError(f"{path}: cannot read the ego poses: {exc.strerror}") from None
    except (UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"{path}: the ego poses are not a UTF-8 CSV text file (a binary file?): {exc}") from None


def _row_values(path: Path, header: tuple[str, ...], rows: list[list[str]]) -> np.ndarray:
    """(len(rows), len(header)) float: each row's numbers, checked finite, in bounds and sorted by time."""
    values = np.empty((len(rows), len(header)))
    for n, row in enumerate(rows):
        try:
            if len(row) != len(header):
                raise ValueError
            values[n] = [float(c) for c in row]
        except ValueError:
            raise InputError(f"{path}: row {n + 1} (line {n + 2}) must hold {len(header)} numbers "
                             f"({','.join(header)}), got {','.join(row)}") from None
        if not np.all(np.isfinite(values[n])):
            raise InputError(f"{path}: row {n + 1} (line {n + 2}) contains NaN or inf")
        _check_bounds(path, n, header, values[n])
        if n and values[n, 0] <= values[n - 1, 0]:
            raise InputError(f"{path}: rows must be sorted by time: row {n + 1} (line {n + 2}, timestamp "
                             f"{values[n, 0]:.6f} s) is not after row {n} ({values[n - 1, 0]:.6f} s)")
    return values


def _translations_quaternions(path: Path, header: tuple[str, ...],
                              values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, 3) translations, metres, and (N, 4) unit quaternions ``[w, x, y, z]`` of the rows' values
    (the 3D header's quaternions normalised; the planar header's yaw about z, at z = 0)."""
    if header == POSE_HEADERS[0]:
        trans, quats = values[:, 1:4], values[:, 4:8]
        norms = np.linalg.norm(quats, axis=1)
        if np.any(norms < 1e-9):
            raise InputError(f"{path}: row {int(np.argmax(norms < 1e-9)) + 1} has a zero quaternion")
        return trans, quats / norms[:, None]
    trans = np.column_stack([values[:, 1:3], np.zeros(len(values))])
    return trans, Rotation.from_euler("z", values[:, 3:4]).as_quat(canonical=True, scalar_first=True)


def _check_bounds(path: Path, n: int, header: tuple[str, ...], row: np.ndarray) -> None:
    """InputError when a row's timestamp or position is outside the ranges above."""
    where = f"{path}: row {n + 1} (line {n + 2})"
    if abs(row[0]) > MAX_TIMESTAMP_S:
        raise InputError(f"{where}: timestamp {row[0]:g} s is beyond {MAX_TIMESTAMP_S:g} s")
    for name, value in zip(header[1:4], row[1:4]):
        if name in ("x", "y", "z") and abs(value) > MAX_EGO_COORDINATE_M:
            raise InputError(f"{where}: {name} = {value:g} m is beyond {MAX_EGO_COORDINATE_M:g} m from the world "
                             f"origin (positions there have no millimetre precision); shift the poses' origin")


#: Ego speeds above this (m/s, about 300 km/h) between two pose rows are warned about:
#: a jump in the poses (a wrong row, a reset) makes every pedestrian seem to race.
MAX_PLAUSIBLE_EGO_SPEED_MPS = 85.0


def _warn_implausible_speed(path: Path, ts: np.ndarray, trans: np.ndarray) -> None:
    if len(ts) < 2:
        return
    speeds = np.linalg.norm(np.diff(trans, axis=0), axis=1) / np.diff(ts)
    fast = np.flatnonzero(speeds > MAX_PLAUSIBLE_EGO_SPEED_MPS)
    if len(fast):
        i = int(fast[0])
        warnings.warn(f"{path}: the ego moves at {speeds[i]:.0f} m/s between rows {i + 1} and {i + 2} (lines {i + 2}-"
                      f"{i + 3}), above the plausible {MAX_PLAUSIBLE_EGO_SPEED_MPS:g} m/s; {len(fast)} such step(s): "
                      f"check the poses (positions must be metres, timestamps seconds)", stacklevel=3)
