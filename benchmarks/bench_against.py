"""Time the model's stages against an earlier revision, in one run, as ratios.

    python benchmarks/bench_against.py REV [--rounds 5] [--frames 100]

Checks REV out into a temporary git worktree and times ``bench_core`` (tracking per frame,
position per pedestrian, 10 and 100 pedestrians; paper and fused) of this tree and of
REV in alternating subprocesses, so both see the same machine load. Prints the median of
each figure and the ratio (this tree / REV); below 1 is faster. Timings on a shared
machine vary: read the ratios, not the milliseconds.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: Run inside each tree: the bench of the paper and the fused method (older trees name the
#: module pedenv.bench and set the method with Config.for_method).
PROBE = """
import json, sys
try:
    from pedenv.apps.bench import bench_core
    from pedenv.localization import configure
    fused = lambda c: configure(c, "fused")
    paper = lambda c: configure(c, "paper")  # Config() is the fused method since issue 12
except ImportError:
    from pedenv.bench import bench_core
    fused = lambda c: c.for_method("fused")
    paper = lambda c: c
from pedenv.config import Config
frames = int(sys.argv[1])
out = {}
for name, cfg in (("paper", paper(Config())), ("fused", fused(Config()))):
    for row in bench_core(n_frames=frames, config=cfg):
        for key in ("tracking_per_frame", "position_per_pedestrian"):
            out[f"{name} {key} {row['pedestrians']} peds"] = row[key]
print(json.dumps(out))
"""


def measure(src: Path, frames: int) -> dict:
    env = {**os.environ, "PYTHONPATH": str(src)}
    done = subprocess.run([sys.executable, "-c", PROBE, str(frames)], env=env, capture_output=True, text=True,
                          check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rev", help="git revision to compare with")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=100)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        other = Path(tmp) / "other"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(other), args.rev], check=True)
        try:
            runs: dict[str, list[dict]] = {"this": [], "rev": []}
            for _ in range(args.rounds):
                runs["this"].append(measure(ROOT / "src", args.frames))
                runs["rev"].append(measure(other / "src", args.frames))
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(other)], check=True)
    print(f"{'figure (ms)':<44}{'this':>10}{args.rev[:10]:>12}{'ratio':>8}")
    for key in runs["this"][0]:
        a = statistics.median(r[key] for r in runs["this"])
        b = statistics.median(r[key] for r in runs["rev"])
        print(f"{key:<44}{a:>10.4f}{b:>12.4f}{a / b:>8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
