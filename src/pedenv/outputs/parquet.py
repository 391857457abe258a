"""The environment model and the evaluation's matched pairs as Parquet tables (pyarrow).

``environment.parquet``: one row per pedestrian and frame (see :data:`ENVIRONMENT_SCHEMA`).
``matches.parquet``: one row per matched prediction/ground-truth pair of an evaluation.

Both are written incrementally with ``pyarrow.parquet.ParquetWriter``, one row group per
``frames_per_row_group`` frames. The guarantee: when a run stops through an exception or
Ctrl-C, ``close()`` (called by the apps in ``finally``) writes the buffered frames and the
footer, so the file holds every finished frame. A process killed outright (SIGKILL, power
loss) leaves no footer and the file cannot be read; ``environment.jsonl`` is the record
that survives that.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Self

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from pedenv.records import Frame
from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.state import EnvironmentState

#: Frames buffered before a row group is written; smaller loses less on a hard kill, larger compresses better.
DEFAULT_FRAMES_PER_ROW_GROUP = 50


_FLOAT64 = pa.float64()


def _vec(n: int, kind: pa.DataType = _FLOAT64) -> pa.DataType:
    return pa.list_(kind, n)


def _points(dim: int) -> pa.DataType:
    return pa.list_(pa.list_(pa.float64(), dim), NUM_KEYPOINTS)


#: Columns of ``environment.parquet``; positions and velocities in the world frame (m, m/s),
#: covariance the x-y position covariance (m^2), keypoints_2d in pixels, keypoints_3d in the world frame.
ENVIRONMENT_SCHEMA = pa.schema([
    ("scene", pa.string()), ("frame", pa.int64()), ("timestamp", pa.float64()),
    ("track_id", pa.int64()), ("age", pa.int64()),
    ("x", pa.float64()), ("y", pa.float64()), ("z", pa.float64()),
    ("vx", pa.float64()), ("vy", pa.float64()),
    ("cov_xx", pa.float64()), ("cov_xy", pa.float64()), ("cov_yy", pa.float64()),
    ("distance", pa.float64()), ("source", pa.string()),
    ("ego_x", pa.float64()), ("ego_y", pa.float64()), ("ego_yaw", pa.float64()),
    ("box", _vec(4)), ("keypoints_2d", _points(2)), ("keypoint_confidence", _vec(NUM_KEYPOINTS)),
    ("keypoints_3d", _points(3)),
    *[(name, kind) for name, kind in (
        ("yaw", _FLOAT64), ("yaw_std", _FLOAT64), ("orientation_availability", pa.string()),
        ("facing_probability", _FLOAT64), ("head_facing_probability", _FLOAT64), ("motion_state", pa.string()),
        ("speed", _FLOAT64), ("speed_std", _FLOAT64), ("horizons", pa.list_(_FLOAT64)),
        ("predicted_xy", pa.list_(_vec(2))), ("predicted_cov", pa.list_(_vec(3))),
        ("conflict_probability", _FLOAT64), ("conflict_time", _FLOAT64), ("conflict_time_std", _FLOAT64),
        ("closest_approach", _FLOAT64), ("closest_approach_std", _FLOAT64), ("closest_approach_time", _FLOAT64),
        ("ego_speed", _FLOAT64), ("ego_yaw_rate", _FLOAT64))],
])
#: The behaviour columns (``Config.behaviour``, :class:`pedenv.state.Behaviour`; null with ``--method paper``):
#: yaw and its std (rad, world), availability and motion state as names, probabilities, speed (m/s),
#: horizons (s) with predicted x-y (m) and covariances ``[xx, xy, yy]`` (m^2), conflict time (s) and
#: closest approach (m), the ego's speed (m/s) and yaw rate (rad/s).
BEHAVIOUR_COLUMNS = tuple(ENVIRONMENT_SCHEMA.names[ENVIRONMENT_SCHEMA.get_field_index("yaw"):])

#: Columns of ``matches.parquet``: predicted and true x-y (world, m), errors (m, %), distance ego-truth (m).
MATCHES_SCHEMA = pa.schema([
    ("scene", pa.string()), ("frame", pa.int64()), ("timestamp", pa.float64()),
    ("track_id", pa.int64()), ("gt_id", pa.int64()),
    ("pred_x", pa.float64()), ("pred_y", pa.float64()), ("gt_x", pa.float64()), ("gt_y", pa.float64()),
    ("abs_error", pa.float64()), ("rel_error_pct", pa.float64()), ("distance", pa.float64()),
])


def _text(name: str) -> str:
    """``name`` as UTF-8 text: a scene named after a file whose name is not UTF-8 keeps ``\\udcff`` escapes."""
    return name.encode("utf-8", "backslashreplace").decode("utf-8")


def _arrow(values: Sequence[object] | np.ndarray, kind: pa.DataType) -> pa.Array:
    """``values`` as an Arrow array of ``kind``; (n, a[, b]) numpy arrays become nested fixed-size lists."""
    if not pa.types.is_fixed_size_list(kind):
        return pa.array(values, type=kind)
    flat = np.ascontiguousarray(values, dtype=np.float64)
    inner = kind.value_type
    n = flat.shape[0]
    if pa.types.is_fixed_size_list(inner):
        leaves = pa.array(flat.reshape(-1), type=inner.value_type)
        return pa.FixedSizeListArray.from_arrays(pa.FixedSizeListArray.from_arrays(leaves, inner.list_size),
                                                 kind.list_size) if n else pa.array([], type=kind)
    return pa.FixedSizeListArray.from_arrays(pa.array(flat.reshape(-1), type=inner), kind.list_size) if n \
        else pa.array([], type=kind)


class _IncrementalTable:
    """Buffers per-frame column dicts and writes a row group every ``frames_per_row_group`` frames."""

    schema: pa.Schema

    def __init__(self, path: str | Path, frames_per_row_group: int = DEFAULT_FRAMES_PER_ROW_GROUP) -> None:
        if not 1 <= int(frames_per_row_group) <= 100_000:
            raise ValueError(f"frames_per_row_group must be in [1, 100000], got {frames_per_row_group}")
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.every = int(frames_per_row_group)
        self._file = self.path.open("wb")  # opened by Python: pyarrow cannot take a name that is not UTF-8
        self._writer = pq.ParquetWriter(self._file, self.schema, compression="zstd")
        self._pending: list[pa.RecordBatch] = []
        self._frames = 0
        self.rows = 0

    def _add(self, columns: dict) -> None:
        """One frame's rows: column name -> array (numpy arrays of (n, ...) go to fixed-size lists)."""
        self._pending.append(
            pa.record_batch([_arrow(columns[f.name], f.type) for f in self.schema], schema=self.schema)
        )
        self._frames += 1
        if self._frames >= self.every:
            self.flush()

    def flush(self) -> None:
        """Write the buffered frames as one row group."""
        pending = [b for b in self._pending if b.num_rows]
        self._pending, self._frames = [], 0
        if not pending:
            return
        table = pa.Table.from_batches(pending, schema=self.schema).combine_chunks()
        self._writer.write_table(table, row_group_size=table.num_rows)
        self.rows += table.num_rows

    def close(self) -> None:
        if self._writer is None:
            return
        try:
            self.flush()
        finally:
            self._writer.close()
            self._writer = None
            self._file.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class EnvironmentTableWriter(_IncrementalTable):
    """``environment.parquet``: a :class:`pedenv.outputs.sinks.FrameSink`, one row per pedestrian and frame."""

    schema = ENVIRONMENT_SCHEMA

    def write(self, state: EnvironmentState, frame: Frame | None = None) -> None:  # noqa: ARG002
        # ``frame``: FrameSink.write's signature; the table holds only the state
        p, n = state.pedestrians, len(state.pedestrians)
        ego = state.ego
        self._add({
            "scene": [_text(state.scene)] * n, "frame": [state.frame_index] * n, "timestamp": [state.timestamp] * n,
            "track_id": p.track_ids.tolist(), "age": p.ages.tolist(),
            "x": p.positions[:, 0].tolist(), "y": p.positions[:, 1].tolist(), "z": p.positions[:, 2].tolist(),
            "vx": p.velocities[:, 0].tolist(), "vy": p.velocities[:, 1].tolist(),
            "cov_xx": p.covariances[:, 0, 0].tolist(), "cov_xy": p.covariances[:, 0, 1].tolist(),
            "cov_yy": p.covariances[:, 1, 1].tolist(), "distance": p.distances.tolist(),
            "source": [str(s) for s in p.sources],
            "ego_x": [float(ego.translation[0])] * n, "ego_y": [float(ego.translation[1])] * n,
            "ego_yaw": [ego.yaw] * n,
            "box": p.boxes, "keypoints_2d": p.keypoints,
            "keypoint_confidence": p.confidences, "keypoints_3d": p.keypoints_3d,
            **behaviour_columns(state),
        })


def behaviour_columns(state: EnvironmentState) -> dict:
    """The :data:`BEHAVIOUR_COLUMNS` of one frame's pedestrians (all null where behaviour is off)."""
    p, n = state.pedestrians, len(state.pedestrians)
    b = p.behaviour
    if b is None:
        return {name: [None] * n for name in BEHAVIOUR_COLUMNS}
    from pedenv.state import AVAILABILITY, MOTION_STATES

    cov = b.predicted_covariances
    return {
        "yaw": b.yaw.tolist(), "yaw_std": b.yaw_std.tolist(),
        "orientation_availability": [AVAILABILITY[int(a)] for a in b.orientation_availability],
        "facing_probability": b.facing_probability.tolist(),
        "head_facing_probability": b.head_facing_probability.tolist(),
        "motion_state": [MOTION_STATES[int(m)] for m in b.motion_state], "speed": b.speed.tolist(),
        "speed_std": b.speed_std.tolist(), "horizons": [b.horizons.tolist()] * n,
        "predicted_xy": b.predicted_positions.tolist(),
        "predicted_cov": np.stack([cov[..., 0, 0], cov[..., 0, 1], cov[..., 1, 1]], axis=-1).tolist(),
        "conflict_probability": b.conflict_probability.tolist(), "conflict_time": b.conflict_time.tolist(),
        "conflict_time_std": b.conflict_time_std.tolist(), "closest_approach": b.closest_approach.tolist(),
        "closest_approach_std": b.closest_approach_std.tolist(),
        "closest_approach_time": b.closest_approach_time.tolist(),
        "ego_speed": [b.ego_speed] * n, "ego_yaw_rate": [b.ego_yaw_rate] * n,
    }


class MatchesTableWriter(_IncrementalTable):
    """``matches.parquet``: the evaluation's matched pairs, one call per labelled frame."""

    schema = MATCHES_SCHEMA

    def write_pairs(self, frame: Frame, track_ids: np.ndarray, gt_ids: np.ndarray, pred_xy: np.ndarray,
                    gt_xy: np.ndarray, abs_error: np.ndarray, rel_error: np.ndarray, distance: np.ndarray) -> None:
        """K matched pairs of one frame: ids (K,), x-y (K, 2) world metres, errors (K,) m and %, distance (K,) m."""
        k = len(track_ids)
        self._add({
            "scene": [_text(frame.scene)] * k, "frame": [frame.index] * k, "timestamp": [frame.timestamp] * k,
            "track_id": np.asarray(track_ids).tolist(), "gt_id": np.asarray(gt_ids).tolist(),
            "pred_x": pred_xy[:, 0].tolist(), "pred_y": pred_xy[:, 1].tolist(),
            "gt_x": gt_xy[:, 0].tolist(), "gt_y": gt_xy[:, 1].tolist(),
            "abs_error": abs_error.tolist(), "rel_error_pct": rel_error.tolist(), "distance": distance.tolist(),
        })
