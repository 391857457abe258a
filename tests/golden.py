"""Assert seeded end-to-end figures against tests/golden_metrics.json (norfair's metrics.txt
habit): the file and its tolerances are kept by benchmarks/golden_metrics.py."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("golden_metrics", ROOT / "benchmarks" / "golden_metrics.py")
golden_metrics = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(golden_metrics)
GOLDEN = json.loads((ROOT / "tests" / "golden_metrics.json").read_text())


def assert_golden(case: str, metrics) -> None:
    """Every figure of ``metrics`` (an evaluation's Metrics) within tolerance of ``case``."""
    assert case in GOLDEN, f"no golden figures for {case}; run benchmarks/golden_metrics.py --write"
    bad = golden_metrics.differences({case: golden_metrics.figures(metrics)}, GOLDEN)
    assert not bad, "\n".join(bad)
