"""Assert seeded end-to-end figures against tests/golden_metrics.json (norfair's metrics.txt
habit): the figures and their tolerances are :mod:`pedenv.evaluation.golden`'s; benchmarks/golden_metrics.py
rewrites the file."""

from __future__ import annotations

import json
from pathlib import Path

from pedenv.evaluation.golden import differences, figures

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = json.loads((ROOT / "tests" / "golden_metrics.json").read_text())


def assert_golden(case: str, metrics) -> None:
    """Every figure of ``metrics`` (an evaluation's Metrics) within tolerance of ``case``."""
    assert case in GOLDEN, f"no golden figures for {case}; run benchmarks/golden_metrics.py --write"
    bad = differences({case: figures(metrics)}, GOLDEN)
    assert not bad, "\n".join(bad)
