"""One typed configuration object; every constant of the paper is a named, validated value.

Defaults are the paper's (Holzbock et al., Sections III-B and III-C) where it gives one.
``Config.to_dict()`` is saved next to every result so a run can be repeated.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field
from pathlib import Path


def _check_range(name: str, value, low=None, high=None, *, low_open=False, high_open=False) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name} must be a number, got {value!r}")
    bad_low = low is not None and (value <= low if low_open else value < low)
    bad_high = high is not None and (value >= high if high_open else value > high)
    if bad_low or bad_high:
        lo = "" if low is None else ("(" if low_open else "[") + f"{low}"
        hi = "" if high is None else f"{high}" + (")" if high_open else "]")
        raise ValueError(f"{name} must be in {lo or '(-inf'}, {hi or 'inf)'}, got {value}")


def _check_choice(name: str, value, choices) -> None:
    if value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")


@dataclass(frozen=True)
class TrackingConfig:
    """Association of skeletons in the image (Sec. III-B).

    giou_threshold: a detection and a track overlap when their generalized IoU is above
        this (in [-1, 1)). The authors' public code uses -0.3. Raising it makes the
        tracker start new tracks more readily; lowering it lets distant boxes be joined.
    max_misses: a track is dropped after this many consecutive frames without a
        detection (the paper: 3). Raising it keeps tracks alive through occlusions.
    yaw_compensation: shift the tracks' pixels by the ego's yaw change before
        association (Eq. 1). Turning it off is an ablation.
    """

    giou_threshold: float = -0.3
    max_misses: int = 3
    yaw_compensation: bool = True

    def __post_init__(self) -> None:
        _check_range("tracking.giou_threshold", self.giou_threshold, -1.0, 1.0, high_open=True)
        if not isinstance(self.max_misses, int) or isinstance(self.max_misses, bool) or self.max_misses < 1:
            raise ValueError(f"tracking.max_misses must be an integer >= 1, got {self.max_misses!r}")


INITIAL_ESTIMATES = ("all-keypoints", "midpoint")


@dataclass(frozen=True)
class PositionConfig:
    """World position of each pedestrian (Sec. III-C, Algorithm 1).

    method: ``paper`` (two-frame ray intersection and height refinement).
    low_confidence_fraction: share of keypoints with the lowest confidence left out of
        the initial estimate (the paper: 0.3). Raising it trusts fewer, surer keypoints.
    initial_estimate: ``all-keypoints`` (the paper) or ``midpoint`` (ablation of
        Sec. IV-D: only the midpoint of the skeleton's hips).
    refine: run the distance and direction refinement (ablation: off).
    person_height_m: the assumed body height re-projected in the refinement (1.7 m).
        Raising it moves every refined pedestrian farther away.
    refinement_steps: number of refinement iterations (the paper: 15).
    refinement_lambda_offset: ``c`` in ``lambda = r + c`` for step ``r`` = 1..steps (the
        paper: 5). Each step scales the distance by ``1 + (h_est / h_orig - 1) / lambda``;
        raising ``c`` makes the refinement move less from the initial estimate.
    min_parallax_rad: rays closer to parallel than this angle do not intersect; the
        position then falls back to the height-based distance.
    max_distance_m: triangulated keypoints farther than this from the camera are
        discarded as degenerate.
    """

    method: str = "paper"
    low_confidence_fraction: float = 0.3
    initial_estimate: str = "all-keypoints"
    refine: bool = True
    person_height_m: float = 1.7
    refinement_steps: int = 15
    refinement_lambda_offset: float = 5.0
    min_parallax_rad: float = 1e-6
    max_distance_m: float = 500.0

    def __post_init__(self) -> None:
        _check_choice("position.method", self.method, POSITION_METHODS)
        _check_range("position.low_confidence_fraction", self.low_confidence_fraction, 0.0, 1.0, high_open=True)
        _check_choice("position.initial_estimate", self.initial_estimate, INITIAL_ESTIMATES)
        _check_range("position.person_height_m", self.person_height_m, 0.3, 2.5)
        if not isinstance(self.refinement_steps, int) or self.refinement_steps < 0:
            raise ValueError(f"position.refinement_steps must be an integer >= 0, got {self.refinement_steps!r}")
        _check_range("position.refinement_lambda_offset", self.refinement_lambda_offset, 0.0, low_open=True)
        _check_range("position.min_parallax_rad", self.min_parallax_rad, 0.0, 0.1)
        _check_range("position.max_distance_m", self.max_distance_m, 1.0)


POSITION_METHODS = ("paper",)


@dataclass(frozen=True)
class KalmanConfig:
    """Constant-velocity Kalman filter on the ground-plane position (Sec. III-C).

    The paper names the filter but not its noise; these defaults were tuned on the
    built-in scenes.

    enabled: filter the positions (off: raw per-frame estimates).
    acceleration_std_mps2: white-noise acceleration of a pedestrian (Q via filterpy's
        ``Q_discrete_white_noise``). Raising it follows turns faster, smooths less.
    measurement_std_m: standard deviation of one position measurement per axis (R),
        as a fraction of the distance plus this floor; see ``measurement_std_rel``.
    measurement_std_rel: relative part of the measurement noise (per metre of distance).
    initial_velocity_std_mps: prior spread of a new track's velocity.
    """

    enabled: bool = True
    acceleration_std_mps2: float = 1.0
    measurement_std_m: float = 0.5
    measurement_std_rel: float = 0.1
    initial_velocity_std_mps: float = 2.0

    def __post_init__(self) -> None:
        _check_range("kalman.acceleration_std_mps2", self.acceleration_std_mps2, 0.0, low_open=True)
        _check_range("kalman.measurement_std_m", self.measurement_std_m, 0.0, low_open=True)
        _check_range("kalman.measurement_std_rel", self.measurement_std_rel, 0.0)
        _check_range("kalman.initial_velocity_std_mps", self.initial_velocity_std_mps, 0.0, low_open=True)


@dataclass(frozen=True)
class Config:
    """Everything the environment model needs besides the data."""

    tracking: TrackingConfig = field(default_factory=TrackingConfig)
    position: PositionConfig = field(default_factory=PositionConfig)
    kalman: KalmanConfig = field(default_factory=KalmanConfig)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "Config":
        parts = {"tracking": TrackingConfig, "position": PositionConfig, "kalman": KalmanConfig}
        unknown = set(data) - set(parts)
        if unknown:
            raise ValueError(f"unknown config section(s): {', '.join(sorted(unknown))}; valid: {', '.join(parts)}")
        built = {}
        for name, kind in parts.items():
            values = data.get(name, {})
            names = {f.name for f in dataclasses.fields(kind)}
            extra = set(values) - names
            if extra:
                raise ValueError(f"unknown field(s) in config.{name}: {', '.join(sorted(extra))}; valid: {', '.join(sorted(names))}")
            built[name] = kind(**values)
        return cls(**built)

    def replace(self, **sections) -> "Config":
        """A copy with some sections' fields changed: ``cfg.replace(position={"refine": False})``."""
        data = self.to_dict()
        for name, values in sections.items():
            if name not in data:
                raise ValueError(f"unknown config section {name!r}")
            data[name] = {**data[name], **values}
        return Config.from_dict(data)

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=2) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> "Config":
        return cls.from_dict(json.loads(Path(path).read_text()))
