"""Where the fused position error comes from on the whole KITTI tracking drives (real motion, modelled perception).

    PYTHONPATH=src python benchmarks/kitti_position_breakdown.py [--scenes 0013,0011] [--ego-poses oxts]

Runs the fused method over the drives as ``pedenv evaluate --dataset kitti-tracking`` does (the
detector model on skeletons rendered from the labels), matches each reported pedestrian as the
paper does (:func:`pedenv.evaluation.matching.match_to_ground_truth`) and prints the mean relative
error of the matched pairs (the figure ``metrics.json`` reports) broken down by drive, distance,
track age (frames), ego speed and the cues that made the estimate (``sources``); beside it the
error's signed part along the viewing ray (+: too far), its size along and across the ray, and
each cue's own error where it had an
estimate (ground, height, triangulation), with the height cue's error had it known each person's
labelled height in place of its track's (``height@H``: what is left when the body height is right). The last line
gives the 1- and 2-sigma coverage of the one-to-one pairs. ``--ego-poses oxts``: GPS/IMU poses
instead of ORB-SLAM3 (0000 and 0001 only).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from pedenv.config import Config
from pedenv.datasets.kitti_drives import KittiDrivesDataset
from pedenv.detection import create_detector
from pedenv.evaluation.matching import match_one_to_one, match_to_ground_truth
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel

DATA = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real" / "kitti" / "tracking_sequences"
MOVING = "0013,0015,0011,0004,0001,0000"
CUES = ("ground", "height", "triangulation")
DISTANCE_BINS = (0, 10, 15, 20, 30, 80)
AGE_BINS = (0, 2, 4, 8, 16, 10000)
SPEED_BINS = (0, 0.5, 3, 6, 10, 40)


def pairs_of(data: KittiDrivesDataset, scene: str, config: Config) -> tuple[list[dict], list[float]]:
    """One dict per matched (reported, labelled) pair of the drive ``scene``: the error's parts
    (metres); and the squared Mahalanobis distance of each one-to-one pair (the coverage's)."""
    model = PedestrianEnvironmentModel(config)
    backend = create_detector(data.default_pose_backend, redetect=config.redetect)
    out, nees, last = [], [], None
    for frame in data.frames(scene):
        frame = replace(frame, detections=backend(frame, model.predict_tracks(frame)))
        state = model.update(frame)
        speed = 0.0 if last is None else float(np.linalg.norm(frame.ego.translation[:2] - last.ego.translation[:2])
                                                / (frame.timestamp - last.timestamp))
        last, gt, peds = frame, frame.ground_truth, state.pedestrians
        if gt is None or not len(peds.track_ids):
            continue
        match = match_to_ground_truth(peds.boxes, peds.positions[:, :2], gt.boxes, gt.positions[:, :2])
        one = match_one_to_one(peds.boxes, gt.boxes)
        for i in np.flatnonzero(one >= 0):
            e = peds.positions[i, :2] - gt.positions[one[i], :2]
            nees.append(float(e @ np.linalg.solve(peds.covariances[i] + 1e-9 * np.eye(2), e)))
        origin = frame.cam_to_world[:2, 3]
        cues = {q.name: q for q in model.locator.last_cues}
        for i in np.flatnonzero(match >= 0):
            truth = gt.positions[match[i], :2]
            ray = (truth - origin) / np.linalg.norm(truth - origin)
            err = peds.positions[i, :2] - truth
            row = {"scene": scene, "dist": float(np.linalg.norm(truth - frame.ego.translation[:2])),
                   "age": int(peds.ages[i]), "speed": speed, "err": err, "along": float(err @ ray),
                   "across": float(err[0] * -ray[1] + err[1] * ray[0]), "sources": str(peds.sources[i]).split(";")[0]}
            for name, q in cues.items():
                if q.valid[i]:
                    row[name] = q.positions[i] - truth
            if "height" in row and gt.heights is not None:  # its range scales with the height it took (the track's)
                used = model.locator.last_heights[i]
                scaled = origin + (cues["height"].positions[i] - origin) * gt.heights[match[i]] / used
                row["height@H"] = scaled - truth
            out.append(row)
    return out, nees


def _rel(rows: list[dict], key: str) -> str:
    values = [100 * np.linalg.norm(r[key]) / r["dist"] for r in rows if key in r]
    return f"{np.mean(values):5.2f} ({len(values)})" if values else "    - (0)"


def line(label: str, rows: list[dict]) -> str:
    """The breakdown's columns for a group of pairs."""
    if not rows:
        return f"{label:24} n=0"
    pct = lambda key: np.mean([100 * r[key] / r["dist"] for r in rows])  # noqa: E731
    size = lambda key: np.mean([100 * abs(r[key]) / r["dist"] for r in rows])  # noqa: E731
    cues = " ".join(f"{c} {_rel(rows, c)}" for c in (*CUES, "height@H"))
    return (f"{label:24} n={len(rows):5} rel {_rel(rows, 'err')[:5]} % | along {pct('along'):+5.2f} %, "
            f"|along| {size('along'):5.2f} |across| {size('across'):4.2f} | {cues}")


def binned(rows: list[dict], key: str, bins: tuple, unit: str) -> list[str]:
    return [line(f"{key} {lo}-{hi} {unit}", [r for r in rows if lo <= r[key] < hi]) for lo, hi in zip(bins, bins[1:])]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data-root", type=Path, default=DATA)
    parser.add_argument("--scenes", default=MOVING, help=f"comma-separated drives (default: {MOVING})")
    parser.add_argument("--ego-poses", default="orbslam3", choices=("orbslam3", "oxts"))
    args = parser.parse_args()
    data = KittiDrivesDataset(args.data_root, ego_poses=args.ego_poses)
    config = configure(Config(), "fused")
    results = [pairs_of(data, scene, config) for scene in args.scenes.split(",")]
    rows = [r for pairs, _ in results for r in pairs]
    nees = np.array([d for _, values in results for d in values])
    print(f"fused, {data.perception}; ego poses {args.ego_poses}; relative error % of the distance (pairs)")
    print(line("all", rows))
    for scene in args.scenes.split(","):
        print(line(f"drive {scene}", [r for r in rows if r["scene"] == scene]))
    for text in (binned(rows, "dist", DISTANCE_BINS, "m") + binned(rows, "age", AGE_BINS, "frames")
                 + binned(rows, "speed", SPEED_BINS, "m/s")):
        print(text)
    for sources in sorted({r["sources"] for r in rows}, key=lambda s: -sum(r["sources"] == s for r in rows)):
        print(line(sources, [r for r in rows if r["sources"] == sources]))
    print(f"one-to-one pairs {len(nees)}: within 1 sigma {100 * np.mean(nees <= 1):.1f} %, "
          f"2 sigma {100 * np.mean(nees <= 4):.1f} %, mean NEES {nees.mean():.2f}")


if __name__ == "__main__":
    main()
