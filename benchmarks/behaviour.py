"""Behaviour cues: orientation on the real samples, and orientation, predicted path,
conflict events, motion state and cost on the synthetic scenes. Prints the tables of docs/behaviour.md.

    PYTHONPATH=src python benchmarks/real_detections.py --mode far --min-score 0.25 --only kitti,nuscenes \\
        --out det-far.npz
    PYTHONPATH=src python benchmarks/behaviour.py --detections det-far.npz
    PYTHONPATH=src python benchmarks/behaviour.py --skip-real --scenes red-light-crossing
    PYTHONPATH=src python benchmarks/behaviour.py --skip-real --seed 1       # other walkers and timings
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np

from pedenv.config import Config
from pedenv.evaluation.behaviour_real import real_orientation
from pedenv.evaluation.behaviour_synthetic import synthetic_behaviour

DEFAULT_SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"


def summarise(errors: list[float]) -> str:
    e = np.asarray(errors, float)
    if not len(e):
        return "| 0 | - | - | - |"
    return (f"| {len(e)} | {np.median(e):.1f} | {100 * np.mean(e <= 22.5):.0f} % | {100 * np.mean(e <= 45):.0f} % |")


def print_real(rows: list[dict]) -> None:
    """The tables of docs/behaviour.md: all matched pedestrians, then by distance and by pixel height."""
    print("\n### Orientation on the real samples (median |error| deg, share within 22.5 / 45 deg)\n")
    print("| estimate | n | median | <= 22.5 | <= 45 |\n|---|---|---|---|---|")
    print("| pedenv (skeleton, one frame) " + summarise([r["pedenv"] for r in rows]))
    print("| always facing the camera " + summarise([r["facing_camera"] for r in rows]))
    walk = [r for r in rows if r["walking"] is not None]
    print("| walking direction (labels; walkers only) " + summarise([r["walking"] for r in walk]))
    print("| pedenv on those walkers " + summarise([r["pedenv"] for r in walk]))
    for name, field, edges in (("distance, m", "distance_m", (0, 15, 30, 1e9)),
                               ("pixel height, px", "height_px", (0, 80, 150, 1e9))):
        print(f"\n| {name} | n | pedenv median | <= 22.5 | <= 45 | facing-camera median | walking median (n) |")
        print("|---|---|---|---|---|---|---|")
        for lo, hi in zip(edges, edges[1:]):
            sel = [r for r in rows if lo <= r[field] < hi]
            walk = [r["walking"] for r in sel if r["walking"] is not None]
            fc = f"{np.median([r['facing_camera'] for r in sel]):.1f}" if sel else "-"
            wk = f"{np.median(walk):.1f} ({len(walk)})" if walk else "- (0)"
            label = f"{lo}-{hi}" if hi < 1e9 else f">= {lo}"
            print(f"| {label} " + summarise([r["pedenv"] for r in sel]) + f" {fc} | {wk} |")


def print_synthetic(rows: list[dict], timing: dict) -> None:
    near = [r for r in rows if r["distance_m"] <= 30.0]
    e = np.array([r["yaw_error_deg"] for r in near])
    avail = np.array([r["yaw_error_deg"] for r in near if r["available"] == 2])
    print("\n### Synthetic orientation (matched pedestrians within 30 m)\n")
    print("| subset | n | median deg | <= 22.5 | <= 45 |\n|---|---|---|---|---|")
    for name, x in (("all", e), ("available", avail)):
        if len(x):
            print(f"| {name} | {len(x)} | {np.median(x):.1f} | {100 * np.mean(x <= 22.5):.0f} % | "
                  f"{100 * np.mean(x <= 45):.0f} % |")
    paths = [r for r in rows if r["in_scene_2s"]]
    print("\n### Predicted path (metres): pedenv's positions ahead against the truth; 'motion' counts the")
    print("predicted displacement alone (from pedenv's own position now); CV: constant velocity from the true state\n")
    print("| pedestrians | n | ADE 1 s | FDE 1 s | ADE 2 s | FDE 2 s | motion FDE 1 s | motion FDE 2 s "
          "| CV FDE 1 s | CV FDE 2 s | motion FDE 2 s / CV |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name, limit in (("within 15 m", 15.0), ("within 30 m", 30.0), ("all", 1e9)):
        sel = [r for r in paths if r["distance_m"] <= limit]
        if not sel:
            continue
        pe, me, ce = (np.array([r[k] for r in sel]) for k in ("pred_err", "motion_err", "cv_err"))
        cells = (pe[:, :4].mean(), pe[:, 3].mean(), pe.mean(), pe[:, 7].mean(), me[:, 3].mean(), me[:, 7].mean(),
                 ce[:, 3].mean(), ce[:, 7].mean())
        print(f"| {name} | {len(sel)} | " + " | ".join(f"{v:.2f}" for v in cells)
              + f" | {me[:, 7].mean() / max(ce[:, 7].mean(), 1e-9):.1f} |")
    ev = [r for r in rows if "true_event" in r]
    tp = [r for r in ev if r["true_event"] and r["predicted_event"]]
    n_true, n_pred = sum(r["true_event"] for r in ev), sum(r["predicted_event"] for r in ev)
    terr = np.array([abs(r["predicted_time"] - r["true_time"]) for r in tp])
    print("\n### Conflict: enters the corridor within 2 s\n")
    print("| pairs | true events | predicted | recall | precision | median time error s | 90 % time error s |")
    print("|---|---|---|---|---|---|---|")
    print(f"| {len(ev)} | {n_true} | {n_pred} | {100 * len(tp) / max(n_true, 1):.1f} % | "
          f"{100 * len(tp) / max(n_pred, 1):.1f} % | {np.median(terr) if len(terr) else 0:.2f} | "
          f"{np.quantile(terr, 0.9) if len(terr) else 0:.2f} |")
    seen = [r for r in ev if not r["turn_ahead"]]
    hits, n_true, n_pred = (sum(r["true_event"] and r["predicted_event"] for r in seen),
                            sum(r["true_event"] for r in seen), sum(r["predicted_event"] for r in seen))
    print(f"\nWithout the pairs whose ego turn begins after now ({len(ev) - len(seen)} pairs, "
          f"{sum(r['true_event'] for r in ev) - n_true} true events): recall {100 * hits / max(n_true, 1):.1f} %, "
          f"precision {100 * hits / max(n_pred, 1):.1f} % ({n_true} true events, {n_pred} predicted)")
    print("\n### Motion state (rows: truth; columns: pedenv)\n")
    print("| pedestrians | truth | n | standing | walking | running |\n|---|---|---|---|---|---|")
    for group, limit in (("within 30 m", 30.0), ("all", 1e9)):
        for name, moving in (("standing", False), ("walking", True)):
            st = np.array([r["state"] for r in rows if r["true_moving"] == moving and r["distance_m"] <= limit])
            print(f"| {group} | {name} | {len(st)} | "
                  + " | ".join(f"{100 * np.mean(st == k):.1f} %" for k in range(3)) + " |")
    per_frame = 1e3 * timing["update_s"] / max(timing["frames"], 1)
    extra = 1e3 * timing["behaviour_s"] / max(timing["frames"], 1)
    print(f"\n### Cost\n\n{timing['frames']} frames, {timing['pedestrians'] / max(timing['frames'], 1):.1f} "
          f"pedestrians per frame: model.update {per_frame:.2f} ms per frame, of which behaviour {extra:.2f} ms "
          f"= {100 * extra / max(per_frame - extra, 1e-9):.1f} % of the rest of update")


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
