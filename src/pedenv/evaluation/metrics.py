"""Evaluation results as a serializable object; printing lives in ``pedenv.evaluation.report``."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

#: Mahalanobis radii of the 1- and 2-sigma ellipses of a 2D Gaussian (39.3 % and 86.5 % inside).
SIGMA_LEVELS = (1.0, 2.0)


@dataclass(frozen=True)
class ErrorSummary:
    """Mean absolute (m) and relative (%) position error over ``count`` matched pedestrians."""

    abs_error_m: float
    rel_error_pct: float
    count: int

    @classmethod
    def of(cls, abs_err: np.ndarray, rel_err: np.ndarray) -> ErrorSummary:
        n = len(abs_err)
        return cls(float(np.mean(abs_err)) if n else float("nan"), float(np.mean(rel_err)) if n else float("nan"), n)


@dataclass
class ErrorSamples:
    """Per-pedestrian samples of one scene, gathered frame by frame."""

    abs_err: list = field(default_factory=list)
    rel_err: list = field(default_factory=list)
    distance: list = field(default_factory=list)
    mahalanobis: list = field(default_factory=list)  # one-to-one pairs (match_one_to_one): may be fewer

    def add(self, abs_err: np.ndarray, rel_err: np.ndarray, distance: np.ndarray, mahalanobis: np.ndarray) -> None:
        self.abs_err.append(abs_err)
        self.rel_err.append(rel_err)
        self.distance.append(distance)
        self.mahalanobis.append(mahalanobis)

    def arrays(self) -> dict[str, np.ndarray]:
        cat = lambda xs: np.concatenate(xs) if xs else np.zeros(0)  # noqa: E731
        return {k: cat(getattr(self, k)) for k in ("abs_err", "rel_err", "distance", "mahalanobis")}


def error_by_distance(distance: np.ndarray, abs_err: np.ndarray, rel_err: np.ndarray, bin_m: float = 1.0) -> list[dict]:
    """Mean errors in distance bins of ``bin_m`` metres (the paper's Fig. 3)."""
    if len(distance) == 0:
        return []
    bins = np.floor(distance / bin_m).astype(int)
    out = []
    for b in np.unique(bins):
        sel = bins == b
        out.append({"distance_m": float(b * bin_m), "abs_error_m": float(abs_err[sel].mean()),
                    "rel_error_pct": float(rel_err[sel].mean()), "count": int(sel.sum())})
    return out


def calibration(mahalanobis: np.ndarray) -> dict:
    """How well the reported covariances describe the errors, from the errors' Mahalanobis
    distances (N,) (NaN: no covariance), each against the person the estimate is of
    (:func:`pedenv.evaluation.matching.match_one_to_one`).

    within_1sigma, within_2sigma: share of errors inside the 1- and 2-sigma ellipses (ideal
    0.393 and 0.865). mean_nees: mean normalized estimation error squared, the mean squared
    Mahalanobis distance (ideal 2, the dimension, for 2D positions; above 2 the covariances
    are too small, below too large); it weighs the tail, which the coverages do not.
    """
    m = mahalanobis[np.isfinite(mahalanobis)]
    if len(m) == 0:
        return {"within_1sigma": float("nan"), "within_2sigma": float("nan"), "mean_nees": float("nan")}
    return {"within_1sigma": float(np.mean(m <= SIGMA_LEVELS[0])),
            "within_2sigma": float(np.mean(m <= SIGMA_LEVELS[1])), "mean_nees": float(np.mean(m**2))}


@dataclass(frozen=True)
class Metrics:
    """Everything ``metrics.json`` holds."""

    overall: ErrorSummary
    scenes: list[tuple[str, ErrorSummary]]
    tracking: dict | None
    timing_ms: dict
    error_by_distance: list[dict]
    calibration: dict
    info: dict
    behaviour: dict | None = None  # the behaviour cues against the labelled future (evaluation.behaviour)

    @classmethod
    def from_samples(cls, per_scene: dict[str, ErrorSamples], tracking: dict | None, timing_ms: dict,
                     info: dict, behaviour: dict | None = None) -> Metrics:
        arrays = {name: s.arrays() for name, s in per_scene.items()}
        every = {k: np.concatenate([a[k] for a in arrays.values()]) if arrays else np.zeros(0)
                 for k in ("abs_err", "rel_err", "distance", "mahalanobis")}
        return cls(
            overall=ErrorSummary.of(every["abs_err"], every["rel_err"]),
            scenes=[(name, ErrorSummary.of(a["abs_err"], a["rel_err"])) for name, a in arrays.items()],
            tracking=tracking, timing_ms=timing_ms,
            error_by_distance=error_by_distance(every["distance"], every["abs_err"], every["rel_err"]),
            calibration=calibration(every["mahalanobis"]), info=info, behaviour=behaviour,
        )

    def to_dict(self) -> dict:
        behaviour = {} if self.behaviour is None else {"behaviour": self.behaviour}
        return {
            "overall": asdict(self.overall),
            "scenes": [{"name": name, **asdict(s)} for name, s in self.scenes],
            "tracking": self.tracking,
            "timing_ms": self.timing_ms,
            "calibration": self.calibration,
            "error_by_distance": self.error_by_distance,
            "info": self.info,
            **behaviour,
        }

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(strict_json(self.to_dict()), indent=2, allow_nan=False) + "\n")


def strict_json(value: Any) -> Any:
    """NaN and inf -> None (in dicts, lists and tuples), so the file is strict JSON."""
    if isinstance(value, dict):
        return {k: strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [strict_json(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value
