"""What an evaluation run returns: its metrics and what the plots need."""

from __future__ import annotations

from dataclasses import dataclass, field

from pedenv.evaluation.metrics import ErrorSamples, Metrics
from pedenv.records import Frame
from pedenv.state import EnvironmentState


@dataclass
class EvaluationResult:
    """Metrics plus what the plots need: per-sample errors and the busiest labelled frame."""

    metrics: Metrics
    samples: dict[str, ErrorSamples]
    busiest: tuple[EnvironmentState, Frame] | None = None
    extras: dict = field(default_factory=dict)
