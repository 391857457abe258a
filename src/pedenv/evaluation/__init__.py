"""Evaluation with the paper's protocol: matching, errors, tracking metrics, outputs."""

from pedenv.evaluation.metrics import ErrorSummary, Metrics
from pedenv.evaluation.runner import EvaluationResult, evaluate_dataset, run_evaluation

__all__ = ["ErrorSummary", "EvaluationResult", "Metrics", "evaluate_dataset", "run_evaluation"]
