"""The whole KITTI tracking drives, both methods side by side: localisation, tracking, behaviour, time.

    PYTHONPATH=src python benchmarks/kitti_tracking.py [--data-root DIR] [--scenes 0013,0015] [--config FILE]

Runs ``pedenv evaluate --dataset kitti-tracking`` in-process (the detector model
``yolo11n-pose-far`` on skeletons rendered from the labels: **real motion, modelled perception**)
with ``--method paper`` and the fused default on the moving drives (0013, 0015, 0011, 0004, 0001,
0000) and the parked ones (0016, 0017), each group evaluated as one dataset, and prints per drive
and per group: relative and absolute position error and count, 1- and 2-sigma coverage, MOTA,
IDF1, ID switches, false positives and misses of the labelled boxes (per drive too: one
evaluation per drive), the predicted path's mean error at
1 / 2 / 3 s beside constant velocity from pedenv's own state, motion-state agreement against the
labelled speed and conflict recall / precision (fused), and the seconds per 1,000 frames of each
method (wall time, with the load average). ``--config``: a pedenv config YAML applied to both.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

from pedenv.apps.evaluate import run_evaluation
from pedenv.config import Config
from pedenv.datasets import open_dataset
from pedenv.localization import configure

DATA = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real" / "kitti" / "tracking_sequences"
GROUPS = {"moving": ("0013", "0015", "0011", "0004", "0001", "0000"), "parked": ("0016", "0017")}


def _f(x: float | None, digits: int = 2) -> str:
    return "-" if x is None or x != x else f"{x:.{digits}f}"


def figures(metrics) -> str:
    """One line of the figures of an evaluation (the module doc's order)."""
    o, t, c, b = metrics.overall, metrics.tracking or {}, metrics.calibration, metrics.behaviour or {}
    m, k = b.get("motion_state") or {}, b.get("conflict") or {}
    fde = " ".join(f"{_f(b.get(f'fde_{h}s_m'))}/{_f(b.get(f'fde_{h}s_constant_velocity_m'))}" for h in (1, 2, 3))
    return (f"{_f(o.rel_error_pct)} % {_f(o.abs_error_m)} m n={o.count} | 1s {_f(100 * c['within_1sigma'], 1)} % "
            f"2s {_f(100 * c['within_2sigma'], 1)} % | MOTA {_f(t.get('mota'), 3)} IDF1 {_f(t.get('idf1'), 3)} "
            f"IDsw {t.get('id_switches', '-')} FP {t.get('false_positives', '-')} FN {t.get('misses', '-')} "
            f"of {t.get('objects', '-')} | FDE 1/2/3 s pred/cv {fde} | state {_f(m.get('agreement'), 3)} "
            f"(n={m.get('count', 0)}) | conflict R {_f(k.get('recall'))} P {_f(k.get('precision'))} "
            f"({k.get('labelled_entries', 0)} entries, {k.get('flagged', 0)} flagged of {k.get('count', 0)})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data-root", type=Path, default=DATA)
    parser.add_argument("--scenes", help="comma-separated drives (default: the moving and the parked groups)")
    parser.add_argument("--config", type=Path, help="a pedenv config YAML for both methods")
    args = parser.parse_args()
    base = Config.load(args.config) if args.config else Config()
    groups = {"selected": tuple(args.scenes.split(","))} if args.scenes else GROUPS
    data = open_dataset("kitti-tracking", args.data_root)
    print(f"KITTI tracking drives: {data.perception}; load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    for group, scenes in groups.items():
        for method in ("paper", "fused"):
            cfg = configure(base, method)  # the method with its own defaults, as --method does
            for scene in (*scenes, None) if len(scenes) > 1 else (None,):
                names = list(scenes) if scene is None else [scene]
                start = time.perf_counter()
                result = run_evaluation(data, scenes=names, config=cfg)
                seconds = time.perf_counter() - start
                frames = sum(1 for name in names for _ in data.frames(name))
                label = group if scene is None else scene
                print(f"{label:7} {method:5} | {figures(result.metrics)} | {1000 * seconds / frames:.1f} s per 1,000 "
                      f"frames ({frames} frames)", flush=True)


if __name__ == "__main__":
    main()
