"""How high the network's lower ankle keypoint sits above the ground under the person, in metres.

    PYTHONPATH=src python benchmarks/real_detections.py --mode far --min-score 0.25 \\
        --only kitti,nuscenes --out det-far.npz
    PYTHONPATH=src python benchmarks/ankle_heights.py --detections det-far.npz

Prints, as JSON, for KITTI (tracking and object samples), nuScenes and both together: the
persons measured, the median and quartiles across persons (each person's median over their
frames), the robust std across persons and the median's offset over the anatomical ankle height
(0.046 x 1.72 m). The KITTI median minus the anatomical height is ``fused.ankle_keypoint_offset_m``;
the robust std of both sets is ``fused.ankle_keypoint_offset_std_m``
(:mod:`pedenv.evaluation.person_offsets` says how each is measured). Real data, real skeletons.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from pedenv.evaluation.person_offsets import ankle_heights
from pedenv.evaluation.real_samples import load_detection_cache
from pedenv.localization.fused.height import ANKLE_FRACTION
from pedenv.synthetic.detector_fit import robust_std

DEFAULT_SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"
#: The body height (m) whose anatomical ankle height the offset is measured over.
BODY_HEIGHT_M = 1.72


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--detections", type=Path, required=True, help="cache written by real_detections.py")
    args = parser.parse_args(argv)
    dets = load_detection_cache(args.detections)
    dets.pop("_meta", None)
    found = ankle_heights(args.samples, dets)
    found["kitti+nuscenes"] = found["kitti"] + found["nuscenes"]
    anatomical = ANKLE_FRACTION * BODY_HEIGHT_M
    summary = {}
    for name, heights in found.items():
        h = np.array(heights)
        if len(h):
            q1, med, q3 = np.percentile(h, [25, 50, 75])
            summary[name] = {"persons": len(h), "median_m": round(float(med), 4),
                             "iqr_m": [round(float(q1), 4), round(float(q3), 4)],
                             "robust_std_m": round(robust_std(h), 4),
                             "offset_over_anatomical_m": round(float(med - anatomical), 4)}
    print(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
