"""Files an evaluation leaves in its output folder besides ``environment.jsonl``."""

from __future__ import annotations

from pathlib import Path

from pedenv.config import Config
from pedenv.evaluation.result import EvaluationResult
from pedenv.visualize.plots import plot_birds_eye, plot_error_by_distance


def write_outputs(result: EvaluationResult, output_dir: Path, config: Config, label: str = "") -> dict[str, Path]:
    """Write ``metrics.json``, ``config.json``, ``birds_eye.png`` and ``error_by_distance.png``."""
    output_dir.mkdir(parents=True, exist_ok=True)
    paths = {"metrics": output_dir / "metrics.json", "config": output_dir / "config.json"}
    result.metrics.save(paths["metrics"])
    config.save(paths["config"])
    label = label or result.metrics.info.get("method", "pedenv")
    paths["error_by_distance"] = plot_error_by_distance(
        {label: result.metrics.error_by_distance}, output_dir / "error_by_distance.png",
        title=f"Absolute error over distance ({result.metrics.info.get('dataset', '')})")
    if result.busiest is not None:
        state, frame = result.busiest
        paths["birds_eye"] = plot_birds_eye(state, output_dir / "birds_eye.png", frame)
    return paths
