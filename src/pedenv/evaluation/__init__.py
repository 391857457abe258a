"""Metrics of the paper's evaluation protocol: matching, errors, tracking metrics, tables."""

from pedenv.evaluation.metrics import ErrorSummary, Metrics
from pedenv.evaluation.result import EvaluationResult

__all__ = ["ErrorSummary", "EvaluationResult", "Metrics"]
