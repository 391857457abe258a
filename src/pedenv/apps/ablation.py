"""The paper's ablations (Sec. IV-D): without refinement, midpoint-only initial estimate."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

from rich.table import Table

from pedenv.apps.evaluate import run_evaluation
from pedenv.config import Config
from pedenv.datasets import Dataset
from pedenv.evaluation.metrics import Metrics, strict_json
from pedenv.evaluation.report import comparison_table
from pedenv.localization import configure
from pedenv.pose.base import PoseBackend

#: Variant name -> paper-method settings changed from the configuration given.
ABLATIONS: dict[str, dict] = {
    "all keypoints + refinement": {"initial_estimate": "all-keypoints", "refine": True},
    "all keypoints, no refinement": {"initial_estimate": "all-keypoints", "refine": False},
    "midpoint + refinement": {"initial_estimate": "midpoint", "refine": True},
    "midpoint, no refinement": {"initial_estimate": "midpoint", "refine": False},
}


def ablation_metrics(dataset: Dataset, *, scenes: Sequence[str] | None = None, config: Config | None = None,
                     pose_backend: str | PoseBackend | None = None) -> list[tuple[str, Metrics]]:
    """Evaluate every variant of :data:`ABLATIONS` on the same frames, with the paper's method
    (``config`` switched to it when it names another)."""
    config = configure(config or Config(), "paper")
    return [(name, run_evaluation(dataset, scenes=scenes, config=config.replace(paper=changes),
                                  pose_backend=pose_backend).metrics)
            for name, changes in ABLATIONS.items()]


def run_ablation(dataset: Dataset, *, scenes: Sequence[str] | None = None, config: Config | None = None,
                 pose_backend: str | PoseBackend | None = None, output_dir: str | Path | None = None) -> Table:
    """Run the ablations, save ``ablation.json`` in ``output_dir`` and return the table."""
    rows = ablation_metrics(dataset, scenes=scenes, config=config, pose_backend=pose_backend)
    if output_dir:
        Path(output_dir).mkdir(parents=True, exist_ok=True)
        data = {name: m.to_dict()["overall"] for name, m in rows}
        (Path(output_dir) / "ablation.json").write_text(json.dumps(strict_json(data), indent=2, allow_nan=False) + "\n")
    return comparison_table(rows, f"Ablation ({dataset.name}), as the paper's Sec. IV-D")
