"""Re-detection of missed tracks on real consecutive frames: tracking with and without it.

    PYTHONPATH=src python benchmarks/redetect_real.py [--samples ../shared/samples/real] [--json OUT]

Runs the environment model (the ``fused`` preset) over the real samples' sequences twice,
with the same main detections (the onnx backend, ``--detection``, person score >= 0.1 as the
preset's low band needs), once with ``redetect.enabled`` and once without, and prints per
dataset: ground-truth boxes, recall (matched / ground truth, IoU >= 0.5), false positives,
ID switches, IDF1, MOTA (motmetrics), the extra network passes per frame and their ms, and
the pairs of reported people with IoU > 0.5 in one frame (a person reported twice).
``--drop P`` removes each main detection with probability P (seeded, the same for both runs):
misses of people the network can see, as longer sequences have them (blur, a passing
occluder); on the samples' 3-8 frames the main pass rarely misses a tracked person.

- KITTI tracking (``kitti/tracking_mini``, sequences 0016 and 0001): the ``pedenv evaluate
  --dataset kitti`` adapter (calibration, ORB-SLAM3 poses); frames 2, 7, 12 (0.5 s apart).
- MOT17 (7 sequences, 4-8 consecutive frames): no calibration, so the whole image is tiled
  for detection, and the tracker works in the image alone (the preset's ground gate and
  memory, which need a real camera, are off); the frames carry a guessed level camera
  (:func:`pedenv.recordings.footage_writer.write_mot17_recording`) the position method needs.
  False positives count people of MOTChallenge's ignore classes (static persons etc.).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT.parent / "shared" / "samples" / "real"
METRICS = ["num_objects", "num_matches", "num_false_positives", "num_switches", "idf1", "mota"]


def kitti_sequences(samples: Path):
    """(name, frames, gt per frame as (ids, boxes), detect) of the KITTI tracking samples."""
    from pedenv.datasets.kitti import KittiTrackingDataset

    data = KittiTrackingDataset(samples / "kitti" / "tracking_mini")
    for name in data.scene_names():
        frames = list(data.frames(name))
        yield f"kitti/{name}", frames, [(f.ground_truth.ids, f.ground_truth.boxes) for f in frames], None


def mot17_sequences(samples: Path, workdir: Path):
    """The same for the MOT17 samples (guessed camera; detection without calibration)."""
    from pedenv.datasets.mot17 import read_sequence, sequence_folders
    from pedenv.recordings.footage import load_recording
    from pedenv.recordings.footage_writer import write_mot17_recording

    for folder in sequence_folders(samples / "mot17"):
        out = write_mot17_recording(folder, workdir / folder.name)
        rec = load_recording(calibration=out / "calibration.yaml", ego_poses=out / "ego_poses.csv",
                             images=out / "images")
        seq = read_sequence(folder)
        gt = []
        for n in seq.frames:
            rows = seq.pedestrians.in_frame(n)
            rows = rows.take(rows.consider)
            gt.append((rows.ids, rows.boxes))
        yield f"mot17/{folder.name}", list(rec.frames()), gt, "whole"


FIELDS = ("keypoints", "confidences", "boxes", "scores")


def load_cache(path: Path | None) -> dict:
    """Main detections by ``<sequence>/<frame index>`` from an .npz written by :func:`save_cache`."""
    from pedenv.records import Detections

    if path is None or not path.is_file():
        return {}
    data = np.load(path)
    keys = {k.rsplit(":", 1)[0] for k in data.files}
    return {k: Detections(*(data[f"{k}:{f}"] for f in FIELDS)) for k in keys}


def save_cache(path: Path, cache: dict) -> None:
    np.savez_compressed(path, **{f"{k}:{f}": getattr(d, f) for k, d in cache.items() for f in FIELDS})


def duplicate_pairs(boxes: np.ndarray, threshold: float = 0.5) -> int:
    """Pairs of boxes (N, 4) px overlapping by IoU > ``threshold``."""
    from pedenv.boxes import iou_matrix

    if len(boxes) < 2:
        return 0
    iou = iou_matrix(boxes, boxes)
    return int((np.triu(iou, 1) > threshold).sum())


def run_sequence(frames, gt, main, config, backend):
    """Tracks over one sequence; returns (motmetrics accumulator, counts)."""
    import motmetrics as mm

    from pedenv.boxes import iou_matrix
    from pedenv.detection.redetect import Redetection
    from pedenv.model import PedestrianEnvironmentModel
    from pedenv.pose.postprocess import frame_image

    model = PedestrianEnvironmentModel(config)
    redetect = Redetection(config.redetect) if config.redetect.enabled else None
    acc = mm.MOTAccumulator(auto_id=True)
    seconds, duplicates = 0.0, 0
    for frame, (ids, boxes), det in zip(frames, gt, main):
        if redetect is not None:
            t0 = time.perf_counter()
            image = frame_image(frame)
            det = redetect(backend.network, image, image.shape[:2], det, model.predict_tracks(frame), backend.decoding)
            seconds += time.perf_counter() - t0
        peds = model.update(replace(frame, detections=det)).pedestrians
        dist = 1.0 - iou_matrix(boxes, peds.boxes)
        dist[dist > 0.5] = np.nan
        acc.update(ids.tolist(), peds.track_ids.tolist(), dist)
        duplicates += duplicate_pairs(peds.boxes)
    crops = redetect.crops if redetect is not None else 0
    found = redetect.redetected if redetect is not None else 0
    return acc, {"frames": len(frames), "crops": crops, "redetected": found, "crop_seconds": seconds,
                 "duplicate_pairs": duplicates}


def summarise(accs, counts) -> dict:
    import motmetrics as mm

    df = mm.metrics.create().compute_many(accs, names=[str(i) for i in range(len(accs))], metrics=METRICS,
                                          generate_overall=True)
    row = df.loc["OVERALL"]
    frames = sum(c["frames"] for c in counts)
    crops = sum(c["crops"] for c in counts)
    return {"gt": int(row["num_objects"]), "recall": float(row["num_matches"] / max(row["num_objects"], 1)),
            "false_positives": int(row["num_false_positives"]), "id_switches": int(row["num_switches"]),
            "idf1": float(row["idf1"]), "mota": float(row["mota"]), "frames": frames,
            "crops_per_frame": crops / max(frames, 1),
            "redetected": sum(c["redetected"] for c in counts),
            "ms_per_crop": 1e3 * sum(c["crop_seconds"] for c in counts) / crops if crops else 0.0,
            "duplicate_pairs": sum(c["duplicate_pairs"] for c in counts)}


def main_ms(value) -> str:
    return "cached" if value is None else f"{value:.0f}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--detection", default="far", choices=["far", "fast"])
    parser.add_argument("--only", choices=["kitti", "mot17"], default=None)
    parser.add_argument("--json", type=Path, default=None, help="Also write the figures here.")
    parser.add_argument("--cache", type=Path, default=None,
                        help="An .npz (outside the repository) keeping the main detections between runs.")
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                        help="A redetect setting for the 'on' run, e.g. --set min_hits=1.")
    parser.add_argument("--drop", type=float, default=0.0,
                        help="Drop each main detection with this probability (0..1), seeded, the same in both "
                             "runs: misses of the main pass on people the network can see (a stress test).")
    parser.add_argument("--seed", type=int, default=0, help="Seed of --drop.")
    args = parser.parse_args(argv)

    from pedenv.config import Config
    from pedenv.detection import create_detector
    from pedenv.localization import configure
    from pedenv.pose.postprocess import frame_image

    fused = configure(Config(), "fused")
    backend = create_detector("onnx", detection=args.detection, score_threshold=fused.tracking.pose_score_threshold)
    image_only = {"ground_gate": 0.0, "memory_s": 0.0}
    settings = {k: json.loads(v) for k, v in (item.split("=", 1) for item in args.set)}
    cache = load_cache(args.cache)
    rng = np.random.default_rng(args.seed)
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        groups = {"kitti": lambda: kitti_sequences(args.samples),
                  "mot17": lambda: mot17_sequences(args.samples, Path(tmp))}
        for group, sequences in groups.items():
            if args.only and group != args.only:
                continue
            runs: dict[str, tuple[list, list]] = {"off": ([], []), "on": ([], [])}
            main_seconds, main_frames = 0.0, 0
            for name, frames, gt, tiling in sequences():
                for f in frames:
                    key = f"{name}/{f.index}"
                    if key not in cache:  # the main pass, timed (frames taken from --cache are not)
                        t0 = time.perf_counter()
                        cache[key] = backend.detect(frame_image(f), None) if tiling == "whole" else backend(f)
                        main_seconds += time.perf_counter() - t0
                        main_frames += 1
                main = [cache[f"{name}/{f.index}"] for f in frames]
                if args.drop > 0:
                    main = [d.take(rng.random(len(d)) >= args.drop) for d in main]
                base = fused if tiling is None else fused.replace(tracking=image_only)
                for variant, enabled in (("off", False), ("on", True)):
                    config = base.replace(redetect={"enabled": enabled, **(settings if enabled else {})})
                    acc, counts = run_sequence(frames, gt, main, config, backend)
                    runs[variant][0].append(acc)
                    runs[variant][1].append(counts)
                print(f"  {name}: {len(frames)} frames", file=sys.stderr)
            for variant, (accs, counts) in runs.items():
                figures = summarise(accs, counts)
                figures["main_ms_per_frame"] = 1e3 * main_seconds / main_frames if main_frames else None
                results[f"{group}/{variant}"] = figures
    if args.cache:
        save_cache(args.cache, cache)
    print(f"re-detection of missed tracks, detection {args.detection}, fused preset, "
          f"'on' with {settings or 'defaults'}" + (f", main detections dropped at p={args.drop}" if args.drop else ""))
    print(f"{'run':12s} {'gt':>5s} {'recall':>7s} {'FP':>4s} {'IDSW':>5s} {'IDF1':>6s} {'MOTA':>6s} "
          f"{'crops/fr':>8s} {'found':>5s} {'ms/crop':>8s} {'ms main':>8s} {'dup':>4s}")
    for key, r in results.items():
        print(f"{key:12s} {r['gt']:5d} {r['recall']:7.3f} {r['false_positives']:4d} {r['id_switches']:5d} "
              f"{r['idf1']:6.3f} {r['mota']:6.3f} {r['crops_per_frame']:8.2f} {r['redetected']:5d} "
              f"{r['ms_per_crop']:8.0f} {main_ms(r['main_ms_per_frame']):>8s} {r['duplicate_pairs']:4d}")
    if args.json:
        args.json.write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
