"""How well the ``stream`` track crops find their people, and how many fit one packed input.

    PYTHONPATH=src python benchmarks/stream_crops.py [--samples ../shared/samples/real/mot17]
        [--score-threshold 0.1] 96,0.35,16 80,0.25,8 ...

Each setting is ``track_person_px,track_margin,track_edge_px`` (:class:`~pedenv.detection.config.StreamConfig`).
For every MOT17 sample frame after a sequence's first, the ground-truth people with visibility
>= 0.5 stand in for tracks: their boxes, moved by a seeded error of 5 % of their height (a
prediction), are cropped as ``stream`` crops its tracks, packed tallest first
(:func:`pedenv.detection.packing.pack_tallest_first`) and run through the network. A person counts as
found when a person in its crop, not cut by an inner crop edge, sure (score >= 0.5) or
plausible (mean keypoint confidence >= 0.5) as :class:`~pedenv.detection.track_search.TrackFinder`
asks, overlaps the truth by IoU >= 0.5. Printed per setting: packed inputs (each one network
unit), people, the share found (by true height: < 60, 60-100, 100-160, >= 160 px) and found per input.
The score threshold is the fused preset's two-band one (what ``pedenv run`` decodes at).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BINS = [0, 60, 100, 160, 100000]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("settings", nargs="+", help="person_px,margin,edge_px")
    parser.add_argument("--samples", type=Path, default=ROOT.parent / "shared" / "samples" / "real" / "mot17")
    parser.add_argument("--score-threshold", type=float, default=0.1)
    args = parser.parse_args(argv)

    from pedenv.boxes import iou_matrix
    from pedenv.datasets import mot17
    from pedenv.detection import create_detector
    from pedenv.detection.config import PLAUSIBLE_KEYPOINT_CONF, SURE_SCORE
    from pedenv.detection.packing import crop_around, pack_tallest_first, run_packed
    from pedenv.images import read_image_rgb

    backend = create_detector("onnx", detection="fast")
    settings = [tuple(float(x) for x in s.split(",")) for s in args.settings]
    hits = {s: np.zeros(len(BINS) - 1) for s in settings}
    people = {s: np.zeros(len(BINS) - 1) for s in settings}
    inputs = dict.fromkeys(settings, 0)
    rng = np.random.default_rng(0)
    for folder in mot17.sequence_folders(args.samples):
        seq = mot17.read_sequence(folder)
        for frame in seq.frames[1:]:
            image = read_image_rgb(seq.image_path(frame))
            size = image.shape[:2]
            rows = seq.pedestrians.in_frame(frame)
            truth = np.clip(rows.boxes[rows.visibility >= 0.5], 0, [size[1], size[0], size[1], size[0]])
            truth = truth[truth[:, 3] - truth[:, 1] >= 16]
            heights = truth[:, 3] - truth[:, 1]
            predicted = truth + rng.normal(0, 0.05, truth.shape) * heights[:, None]
            for s in settings:
                crops = [replace(crop_around(b, size, s[0], s[1], 3.5, (384, 640)), edge_px=s[2]) for b in predicted]
                placed = pack_tallest_first(crops, (384, 640))
                decoding = replace(backend.decoding, score_threshold=args.score_threshold)
                results, passes = run_packed(backend.network.infer_many, image, placed, (384, 640), decoding)
                inputs[s] += len(passes)
                for p, (found, cut) in zip(placed, results):
                    b = np.digitize(heights[p.item], BINS) - 1
                    people[s][b] += 1
                    sure = found.scores >= SURE_SCORE
                    good = ~cut & (sure | (found.confidences.mean(axis=1) >= PLAUSIBLE_KEYPOINT_CONF))
                    if good.any() and iou_matrix(truth[p.item:p.item + 1], found.boxes[good]).max() >= 0.5:
                        hits[s][b] += 1
    print(f"{'setting':>14s} {'inputs':>6s} {'people':>6s} {'found':>6s} {'per input':>9s}  "
          "by height (<60, 60-100, 100-160, >=160)")
    for s in settings:
        share = hits[s].sum() / max(people[s].sum(), 1)
        print(f"{','.join(f'{x:g}' for x in s):>14s} {inputs[s]:6d} {int(people[s].sum()):6d} {share:6.3f} "
              f"{hits[s].sum() / max(inputs[s], 1):9.1f}  "
              + " ".join(f"{int(a)}/{int(b)}" for a, b in zip(hits[s], people[s])))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
