"""Behaviour cues (issue 22): orientation on the real samples, and orientation, predicted path,
conflict events, motion state and cost on the synthetic scenes. Prints the tables of docs/behaviour.md.

    PYTHONPATH=src python benchmarks/real_detections.py --mode far --min-score 0.25 --only kitti,nuscenes \\
        --out /tmp/det-far.npz
    PYTHONPATH=src python benchmarks/behaviour.py --detections /tmp/det-far.npz
    PYTHONPATH=src python benchmarks/behaviour.py --skip-real --scenes red-light-crossing
    PYTHONPATH=src python benchmarks/behaviour.py --skip-real --seed 1       # other walkers and timings
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from behaviour_real import print_real, real_orientation  # noqa: E402
from behaviour_synthetic import print_synthetic, synthetic_behaviour  # noqa: E402
from real_detections import DEFAULT_SAMPLES  # noqa: E402

from pedenv.config import Config  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--detections", type=Path, default=None, help="cached real detections (.npz)")
    parser.add_argument("--skip-real", action="store_true")
    parser.add_argument("--skip-synthetic", action="store_true")
    parser.add_argument("--scenes", default="", help="comma-separated synthetic scenes (default: all)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic scenes")
    parser.add_argument("--profile", default=None, help="detector-model profile (default: its default)")
    parser.add_argument("--duration", type=float, default=None, help="seconds per scene (default: each scene's own)")
    parser.add_argument("--terrain", action="store_true", help="rolling terrain instead of flat ground")
    args = parser.parse_args(argv)
    print(f"load: {os.getloadavg()[0]:.2f} (1-minute average)")
    if not args.skip_real:
        if args.detections is None:
            parser.error("--detections is needed for the real samples (or --skip-real)")
        print_real(real_orientation(args.samples, args.detections, Config()))
    if not args.skip_synthetic:
        names = [n for n in args.scenes.split(",") if n] or None
        rows, timing = synthetic_behaviour(args.seed, args.profile, names, args.duration, args.terrain)
        print_synthetic(rows, timing)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
