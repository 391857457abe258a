"""What the cascade for small people adds: ``far`` with and without it on the real samples.

    PYTHONPATH=src python benchmarks/cascade_real.py [--samples ../shared/samples/real] [--json out.json]

Prints recall by goal height (40-80 px, >= 80 px), precision and network units per image for
``far`` with the cascade off and on (:class:`pedenv.detection.config.CascadeConfig`), and
optionally for variants of its fields (``--variant verify_score=0.25,person_px=96``).
"""

from __future__ import annotations

import argparse
import json
import os
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT.parent / "shared" / "samples" / "real"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--variant", action="append", default=[],
                        help="cascade fields of one more variant, e.g. verify_score=0.25,person_px=96")
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args(argv)

    from pedenv.apps.evaluate_detections import evaluate_detections
    from pedenv.detection.config import DetectionConfig

    base = DetectionConfig.named("far")
    variants = {"far, no cascade": replace(base, cascade=replace(base.cascade, enabled=False)), "far + cascade": base}
    for text in args.variant:
        changes = {k: type(getattr(base.cascade, k))(float(v)) for k, v in (kv.split("=") for kv in text.split(","))}
        variants[f"far + cascade {text}"] = replace(base, cascade=replace(base.cascade, **changes))
    results = {}
    print(f"load {os.getloadavg()[0]:.1f}")
    print(f"{'variant':46s} {'40-80 px':>14s} {'>= 80 px':>14s} {'precision':>9s} {'units':>6s} {'ms':>6s}")
    for name, config in variants.items():
        report = evaluate_detections(args.samples, detection=config)
        block = report["summary"]["all"]
        goals = {b["bin"]: b for b in block["by_goal_height"]}
        row = {"recall_40_80": goals["40-80"]["recall"], "found_40_80": goals["40-80"]["found"],
               "persons_40_80": goals["40-80"]["persons"], "recall_80_up": goals[">=80"]["recall"],
               "precision": block["precision"], "units": report["cost"]["all"]["units_per_frame"],
               "ms": block["ms_per_frame"]}
        results[name] = row
        found = f"{100 * row['recall_40_80']:5.1f} % ({row['found_40_80']}/{row['persons_40_80']})"
        print(f"{name:46s} {found} {100 * row['recall_80_up']:6.1f} % {100 * row['precision']:8.1f} % "
              f"{row['units']:6.2f} {row['ms']:6.0f}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
