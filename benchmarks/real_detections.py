"""Run the real pose network once over the real samples and cache its raw detections.

The cache (an ``.npz`` outside the repository: the samples' licences forbid shipping
anything derived image by image) holds, per image, the persons the network scores above
``--min-score`` (0.05 by default, below the backend's 0.25, so confidence thresholds can be
studied afterwards): keypoints (N, 17, 2) px, keypoint confidences (N, 17), boxes (N, 4) px
and person scores (N,). :mod:`fit_detector_model` reads it.

Mode ``single``: today's whole-frame pass, the input chosen by
:func:`pedenv.pose.models.choose_input_size` (384x640 for frames at least 16:10 wide, else
640x640), i.e. the cached input closest to the frame's aspect. ``--input HxW`` forces one.
Mode ``native``: the whole frame at its own resolution (sides rounded up to 32 px) with a
dynamic-input model (``--model``): what the network sees without downscaling, a reference
for the tiled modes. Modes ``fast`` and ``far``: the onnx backend's detection modes
(``OnnxPose(detection=...)``, the far band from each sample's calibration); run them with
``--min-score 0.25`` (their merge runs at the backend's threshold).

    PYTHONPATH=src python benchmarks/real_detections.py --out det-single.npz
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from pedenv.evaluation.real_samples import sample_images

DEFAULT_SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--out", type=Path, required=True,
                        help="the .npz cache to write (keep it out of the repository)")
    parser.add_argument("--mode", choices=["single", "native", "fast", "far"], default="single")
    parser.add_argument("--model", type=Path, default=None,
                        help="ONNX model; mode native needs one with a dynamic input (ultralytics export dynamic=True)")
    parser.add_argument("--input", default=None, help="force one network input HxW (default: per image)")
    parser.add_argument("--min-score", type=float, default=0.05)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--only", default="", help="comma-separated key prefixes to run (e.g. kitti,nuscenes)")
    args = parser.parse_args(argv)

    import cv2

    from pedenv.detection import create_detector
    from pedenv.pose.models import choose_input_size

    backends: dict = {}
    arrays: dict[str, np.ndarray] = {}
    inputs = []
    t0 = time.perf_counter()
    prefixes = tuple(p for p in args.only.split(",") if p)
    for key, path, geometry in sample_images(args.samples):
        if prefixes and not key.startswith(prefixes):
            continue
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if bgr is None:
            raise SystemExit(f"{path}: not a readable image")
        rgb = np.ascontiguousarray(bgr[..., ::-1])
        if args.mode in ("fast", "far"):
            if "mode" not in backends:
                backends["mode"] = create_detector("onnx", model_path=args.model, detection=args.mode,
                                                       score_threshold=args.min_score, threads=args.threads)
            det = backends["mode"].detect(rgb, geometry)
            size = args.mode
        elif args.input:
            size = args.input
        elif args.mode == "native":  # the whole frame at its own resolution, sides rounded up to the stride
            size = "{}x{}".format(*(-(-np.array(rgb.shape[:2]) // 32) * 32))
        else:
            size = "{}x{}".format(*choose_input_size(rgb.shape[1], rgb.shape[0]))
        if args.mode not in ("fast", "far"):
            if size not in backends:
                backends[size] = create_detector("onnx", model_path=args.model, input_size=size,
                                                     score_threshold=args.min_score, threads=args.threads)
            det = backends[size].detect(rgb)
        for name in ("keypoints", "confidences", "boxes", "scores"):
            arrays[f"{key}|{name}"] = np.asarray(getattr(det, name), np.float32)
        inputs.append(f"{key}={size}")
        print(f"{key}: {len(det)} persons (input {size})", file=sys.stderr)
    arrays["_meta|inputs"] = np.array(inputs)
    arrays["_meta|mode"] = np.array([args.mode])
    args.out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(args.out, **arrays)
    print(f"{len(inputs)} images in {time.perf_counter() - t0:.0f} s -> {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
