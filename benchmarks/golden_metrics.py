"""The seeded end-to-end figures the tests assert: compute them, compare them, or write them.

    python benchmarks/golden_metrics.py            # compute and compare with tests/golden_metrics.json
    python benchmarks/golden_metrics.py --write    # compute and write the file (after a deliberate change)
    python benchmarks/golden_metrics.py --full     # also the README's whole-set figures (minutes)

Each case is one seeded evaluation on the built-in synthetic scenes. The tests
(tests/test_end_to_end.py, tests/localization/fused/test_compare_end_to_end.py) read the
file and assert each figure within its tolerance, so a change that moves a figure must
say so by rewriting the file in the same commit.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from pedenv.evaluation.golden import differences, figures

GOLDEN = Path(__file__).resolve().parents[1] / "tests" / "golden_metrics.json"

TERRAIN_SCENES = ["standing-pedestrians", "drive-30kmh-sidewalk"]


def cases(full: bool = False) -> dict:
    """Case name -> a function computing its metrics."""
    from pedenv.apps.demo import builtin_scenes
    from pedenv.apps.evaluate import run_evaluation
    from pedenv.config import Config
    from pedenv.datasets.memory import MemoryDataset
    from pedenv.localization import configure
    from pedenv.synthetic import generate_scenes

    flat = lambda: MemoryDataset(builtin_scenes(seed=0), name="flat")  # noqa: E731
    terrain2 = lambda: MemoryDataset(generate_scenes(0, TERRAIN_SCENES, terrain=True, duration_s=8.0),  # noqa: E731
                                     name="terrain-seed0")

    def run(data, method: str, backend: str, **paper):
        config = configure(Config().replace(paper=paper) if paper else Config(), method)
        return run_evaluation(data, config=config, pose_backend=backend).metrics

    table = {
        "flat7/paper/ground-truth": lambda: run(flat(), "paper", "ground-truth"),
        "flat7/paper-no-refinement/ground-truth": lambda: run(flat(), "paper", "ground-truth", refine=False),
        "terrain2/paper/ground-truth": lambda: run(terrain2(), "paper", "ground-truth"),
        "terrain2/fused/ground-truth": lambda: run(terrain2(), "fused", "ground-truth"),
        "terrain2/paper/detector-model": lambda: run(terrain2(), "paper", "detector-model"),
        "terrain2/fused/detector-model": lambda: run(terrain2(), "fused", "detector-model"),
    }
    if full:
        terrain7 = lambda: MemoryDataset(builtin_scenes(seed=0, terrain=True), name="terrain7")  # noqa: E731
        table.update({
            "flat7/paper/detector-model": lambda: run(flat(), "paper", "detector-model"),
            "terrain7/paper/ground-truth": lambda: run(terrain7(), "paper", "ground-truth"),
            "terrain7/fused/ground-truth": lambda: run(terrain7(), "fused", "ground-truth"),
            "terrain7/paper/detector-model": lambda: run(terrain7(), "paper", "detector-model"),
            "terrain7/fused/detector-model": lambda: run(terrain7(), "fused", "detector-model"),
        })
    return table


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write tests/golden_metrics.json")
    parser.add_argument("--full", action="store_true", help="also the whole-set figures of the README")
    parser.add_argument("--only", default="", help="comma-separated case names")
    args = parser.parse_args()
    only = {c for c in args.only.split(",") if c}
    measured = {}
    for name, compute in cases(args.full).items():
        if only and name not in only:
            continue
        measured[name] = figures(compute())
        print(name, json.dumps(measured[name]), flush=True)
    golden = json.loads(GOLDEN.read_text()) if GOLDEN.exists() else {}
    if args.write:
        GOLDEN.write_text(json.dumps({**golden, **measured}, indent=2, sort_keys=True) + "\n")
        print(f"wrote {GOLDEN}")
        return 0
    bad = differences(measured, golden)
    print("\n".join(bad) if bad else "all figures within tolerance of the golden file")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
