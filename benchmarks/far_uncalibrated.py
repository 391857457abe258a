"""``far`` on single images without a calibration (as ``pedenv detect street.jpg`` runs) and with one.

    PYTHONPATH=src python benchmarks/far_uncalibrated.py [--samples ../shared/samples/real]

On the calibrated real samples (KITTI, nuScenes: people 38-165 px tall), ``far`` runs once
with no calibration (the band's rows fitted to the people the coarser passes find, or, with
too few of them, the finest level over the whole image) and once with the samples' calibration
(what ``pedenv detect --calibration`` and ``pedenv run`` do). Prints recall by goal height,
persons found and network units per image for each dataset.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT.parent / "shared" / "samples" / "real"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    args = parser.parse_args(argv)

    from pedenv.detection import create_detector
    from pedenv.evaluation.detections import kitti_samples, match_detections, nuscenes_samples, summarize
    from pedenv.images import read_image_rgb

    pose = create_detector("onnx", detection="far")
    print(f"load {os.getloadavg()[0]:.1f}")
    for dataset, samples in (("kitti", kitti_samples(args.samples / "kitti")),
                             ("nuscenes", nuscenes_samples(args.samples / "nuscenes-0061"))):
        images = [read_image_rgb(s.image_path) for s in samples]
        for how in ("no calibration", "calibration"):
            matches, units = [], 0.0
            for s, image in zip(samples, images):
                dets = pose.detect(image, None if how == "no calibration" else s.geometry)
                units += sum(p.input_size[0] * p.input_size[1] for p in pose.last_passes) / (384 * 640)
                matches.append(match_detections(s, dets.boxes, dets.scores))
            block = summarize(samples, matches, [0.0] * len(samples))["all"]
            goals = {b["bin"]: b for b in block["by_goal_height"]}
            cells = "  ".join(f"{k} px {g['found']}/{g['persons']}" for k, g in goals.items())
            print(f"{dataset:9s} {how:15s} found {block['found']}/{block['persons']}  {cells}  "
                  f"units/image {units / len(samples):.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
