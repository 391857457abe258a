"""The detection modes with the network's passes batched and one by one, on the CPU or a GPU.

``OnnxPose`` runs the inputs of one size that a step hands the network together as one batch
(``SessionConfig.batch``; by default on a GPU only) or one after another. This script times
``fast``, ``far`` and ``stream`` on the 1600x900 benchmark frame of ``pedenv bench`` (a level
camera 1.5 m high, so the far bands apply) with ``batch`` off and on, alternating the two in
every round so that both see the same load, and prints per mode and setting: the median and
minimum ms per frame, the network passes per frame, the persons found, and the provider.

    python benchmarks/detection_batching.py --device cuda --rounds 3 --frames 20
"""

from __future__ import annotations

import argparse
import json
import os
import time

import cv2
import numpy as np

from pedenv.detection import create_detector
from pedenv.detection.geometry import CameraGeometry
from pedenv.images import read_image_rgb
from pedenv.pose.timing import benchmark_image
from pedenv.records import Camera

MODES = ("fast", "far", "stream")


def time_mode(detector, mode: str, image: np.ndarray, geometry: CameraGeometry, frames: int,
              start_index: int) -> tuple[list[float], int, int]:
    """ms per frame over ``frames`` frames, the passes of the last frame and the persons it found."""
    times = []
    found = 0
    for i in range(start_index, start_index + frames):
        start = time.perf_counter()
        if mode == "stream":
            persons = detector.detect_frame(image, geometry, 0.1 * i)
        else:
            persons = detector.detect(image, geometry)
        times.append(1e3 * (time.perf_counter() - start))
        found = len(persons)
    return times, len(detector.last_passes), found


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--device", default="auto", help="auto, cpu or cuda")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--frames", type=int, default=10, help="timed frames per mode, setting and round")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--modes", default=",".join(MODES))
    parser.add_argument("--image", default=None, help="a street photo scaled to 1600x900 instead of "
                        "pedenv bench's frame (ultralytics' bus.jpg where ultralytics is installed)")
    parser.add_argument("--output-json", default=None)
    args = parser.parse_args()

    image = benchmark_image() if args.image is None else cv2.resize(read_image_rgb(args.image), (1600, 900))
    geometry = CameraGeometry.level(Camera.from_fov().intrinsics, 1.5)
    rows = []
    for mode in args.modes.split(","):
        detectors = {batch: create_detector("onnx", detection=mode, device=args.device, threads=args.threads,
                                            batch=batch) for batch in (False, True)}
        first_ms = {}
        for batch, detector in detectors.items():  # the first frame: session start and each shape's set-up
            start = time.perf_counter()
            time_mode(detector, mode, image, geometry, 1, 0)
            first_ms[batch] = 1e3 * (time.perf_counter() - start)
        times: dict[bool, list[float]] = {False: [], True: []}
        passes, found = {}, {}
        for r in range(args.rounds):
            for batch, detector in detectors.items():
                t, passes[batch], found[batch] = time_mode(detector, mode, image, geometry, args.frames,
                                                           1 + r * args.frames)
                times[batch] += t
        for batch, detector in detectors.items():
            rows.append({"mode": mode, "batch": batch, "ms_median": float(np.median(times[batch])),
                         "ms_min": float(np.min(times[batch])), "first_frame_ms": first_ms[batch],
                         "passes": passes[batch], "persons": found[batch],
                         "provider": detector.network.provider, "frames": len(times[batch]),
                         "load": os.getloadavg()[0]})
    print(f"{'mode':7} {'batch':6} {'median ms':>10} {'min ms':>8} {'first ms':>9} {'passes':>6} "
          f"{'persons':>7}  provider")
    for row in rows:
        print(f"{row['mode']:7} {str(row['batch']):6} {row['ms_median']:10.1f} {row['ms_min']:8.1f} "
              f"{row['first_frame_ms']:9.0f} {row['passes']:6d} {row['persons']:7d}  {row['provider']}")
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    if args.output_json:
        with open(args.output_json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
