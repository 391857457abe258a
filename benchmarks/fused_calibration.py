"""How well the fused method's covariances describe its errors: real samples and synthetic scenes.

Real samples with 3D ground truth (KITTI tracking 0016 frames 2/7/12, KITTI object 000000,
the five nuScenes cameras): the network's cached detections (``benchmarks/real_detections.py``)
scoring above 0.25 that match a ground-truth box (IoU >= 0.5) are placed by the fused method
frame by frame (no track history: ground and height cues), and the errors in the ground plane
are compared with the reported covariance (frame-to-frame plus per-person part): 1- and
2-sigma coverage and mean NEES (ideal 0.393, 0.865 and 2). The paper's method is placed on
the same detections.

Synthetic scenes (rolling terrain, seed 0): ``compare_methods`` paper vs fused with the
detector model of ``--profile``: relative error, MOTA, IDF1 and ID switches of both, and
the coverage and NEES;
with ``--breakdown`` also where the fused error and NEES come from (false positives,
people matched to a neighbour, their own person; :func:`nees_breakdown`).

    PYTHONPATH=src python benchmarks/fused_calibration.py --detections det-far.npz \
        --profile yolo11n-pose-far --breakdown
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from pedenv.boxes import greedy_match, iou_matrix
from pedenv.config import Config
from pedenv.evaluation.metrics import calibration
from pedenv.evaluation.real_samples import place, real_frames
from pedenv.localization import configure
from pedenv.records import Detections, Frame

SCORE = 0.25
DEFAULT_SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"


def real_errors(samples: Path, detections: Path, config: Config) -> dict:
    data = np.load(detections)
    rows = {"paper": [], "fused": []}
    for key, frame, gt_boxes, gt_xy in real_frames(samples):
        if f"{key}|scores" not in data.files:
            continue
        keep = data[f"{key}|scores"] > SCORE
        det = Detections(data[f"{key}|keypoints"][keep].astype(float), data[f"{key}|confidences"][keep].astype(float),
                         data[f"{key}|boxes"][keep].astype(float), data[f"{key}|scores"][keep].astype(float))
        if len(det) == 0:
            continue
        pairs = greedy_match(iou_matrix(det.boxes, gt_boxes), det.scores, 0.5)
        if not pairs:
            continue
        frame = Frame(frame.index, frame.timestamp, frame.camera, frame.ego, detections=det, scene=frame.scene)
        origin = frame.cam_to_world[:2, 3]
        d_idx, g_idx = np.array(pairs).T
        for method in rows:
            xy, cov, sources = place(method, frame, config)
            err = xy[d_idx] - gt_xy[g_idx]
            dist = np.linalg.norm(gt_xy[g_idx] - origin, axis=1)
            c = cov[d_idx]
            maha = (np.sqrt(np.einsum("ni,nij,nj->n", err, np.linalg.inv(c), err)) if method == "fused"
                    else np.full(len(err), np.nan))
            bearing = (gt_xy[g_idx] - origin) / dist[:, None]
            along = (err * bearing).sum(1)
            across = err[:, 0] * -bearing[:, 1] + err[:, 1] * bearing[:, 0]
            sig_across = np.sqrt(np.einsum("ni,nij,nj->n", np.c_[-bearing[:, 1], bearing[:, 0]], c,
                                           np.c_[-bearing[:, 1], bearing[:, 0]]))
            for i in range(len(err)):
                rows[method].append({"key": key, "distance_m": float(dist[i]), "along_m": float(along[i]),
                                     "across_m": float(across[i]), "sigma_across_m": float(sig_across[i]),
                                     "rel_error_pct": float(100 * np.linalg.norm(err[i]) / dist[i]),
                                     "mahalanobis": float(maha[i]), "source": str(sources[d_idx[i]])})
    out = {}
    for method, r in rows.items():
        maha = np.array([x["mahalanobis"] for x in r])
        out[method] = {"count": len(r), "rel_error_pct": float(np.mean([x["rel_error_pct"] for x in r])),
                       "mean_along_m": float(np.mean([x["along_m"] for x in r])),
                       **(calibration(maha) if method == "fused" else {}), "persons": r}
    return out


def synthetic(profile: str, scenes: list[str] | None, config: Config, duration_s: float) -> dict:
    from pedenv.apps.compare import compare_methods
    from pedenv.datasets.memory import MemoryDataset
    from pedenv.synthetic import generate_scenes

    data = MemoryDataset(generate_scenes(0, scenes, terrain=True, duration_s=duration_s), name="terrain-seed0")
    results = compare_methods(data, pose_backend=f"detector-model:{profile}", config=config)
    tracking = ("mota", "idf1", "id_switches")
    return {m: {"count": r.metrics.overall.count, "rel_error_pct": r.metrics.overall.rel_error_pct,
                **r.metrics.calibration, **{k: (r.metrics.tracking or {}).get(k) for k in tracking}}
            for m, r in results.items()}


def nees_breakdown(profile: str, config: Config, duration_s: float) -> dict:
    """Where the fused method's error and NEES on the synthetic scenes come from, under the
    paper's matching: each match is a false positive (its keypoints lie off every true
    skeleton: median miss over 5 px and 10 % of the height), a person matched to a
    neighbour (the nearest overlapping box in x-y is someone else's), or the person
    itself; with each group's count, share of the summed relative error and mean NEES,
    and the NEES of the non-ghost matches against their own person."""
    from dataclasses import replace

    from pedenv.datasets.memory import MemoryDataset
    from pedenv.detection import create_detector
    from pedenv.evaluation.matching import match_to_ground_truth
    from pedenv.model import PedestrianEnvironmentModel
    from pedenv.synthetic import generate_scenes

    data = MemoryDataset(generate_scenes(0, terrain=True, duration_s=duration_s), name="terrain-seed0")
    backend = create_detector(f"detector-model:{profile}")
    model = PedestrianEnvironmentModel(configure(config, "fused"))
    rows = []  # (group, relative error %, NEES, NEES against the own person)
    for scene in data.scene_names():
        model.reset()
        for frame in data.frames(scene):
            frame = replace(frame, detections=backend(frame))
            peds, gt = model.update(frame).pedestrians, frame.ground_truth
            if gt is None or not len(peds.track_ids) or gt.keypoints is None:
                continue
            match = match_to_ground_truth(peds.boxes, peds.positions[:, :2], gt.boxes, gt.positions[:, :2])
            inv = np.linalg.inv(peds.covariances + 1e-9 * np.eye(2))
            for i in np.flatnonzero(match >= 0):
                miss = np.median(np.linalg.norm(gt.keypoints - peds.keypoints[i], axis=-1), axis=1)
                tall = np.ptp(gt.keypoints[..., 1], axis=1)
                own = int(np.argmin(miss / np.maximum(tall, 1.0)))
                ghost = miss[own] > max(5.0, 0.1 * tall[own])
                e = peds.positions[i, :2] - gt.positions[match[i], :2]
                e_own = peds.positions[i, :2] - gt.positions[own, :2]
                rel = 100.0 * np.linalg.norm(e) / np.linalg.norm(gt.positions[match[i], :2] - frame.ego.translation[:2])
                group = "false positive" if ghost else ("neighbour" if own != match[i] else "own person")
                rows.append((group, rel, float(e @ inv[i] @ e), np.nan if ghost else float(e_own @ inv[i] @ e_own)))
    rel_sum = sum(r[1] for r in rows)
    out = {g: {"count": len(sel), "share_of_error_pct": 100.0 * sum(r[1] for r in sel) / rel_sum,
               "mean_nees": float(np.mean([r[2] for r in sel]))}
           for g in ("false positive", "neighbour", "own person") if (sel := [r for r in rows if r[0] == g])}
    out["all"] = {"count": len(rows), "rel_error_pct": rel_sum / len(rows),
                  "mean_nees": float(np.mean([r[2] for r in rows])),
                  "mean_nees_against_own_person": float(np.nanmean([r[3] for r in rows]))}
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--detections", type=Path, help="network detections cached by real_detections.py")
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--profile", default=None, help="detector-model profile for the synthetic scenes")
    parser.add_argument("--scenes", default="", help="comma-separated synthetic scene names (default: all)")
    parser.add_argument("--duration", type=float, default=8.0, help="seconds of each synthetic scene")
    parser.add_argument("--persons", action="store_true", help="print every real person's row")
    parser.add_argument("--breakdown", action="store_true",
                        help="with --profile: the synthetic error and NEES by false positives, neighbours, own person")
    args = parser.parse_args(argv)
    config = Config()
    result = {}
    if args.detections:
        result["real"] = real_errors(args.samples, args.detections, config)
        if not args.persons:
            for m in result["real"].values():
                m.pop("persons")
    if args.profile:
        result["synthetic"] = synthetic(args.profile, [s for s in args.scenes.split(",") if s] or None, config,
                                        args.duration)
        if args.breakdown:
            result["synthetic_breakdown"] = nees_breakdown(args.profile, config, args.duration)
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
