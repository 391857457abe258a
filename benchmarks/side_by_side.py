"""Passes side by side against one after another (``SessionConfig.side_by_side``), on the CPU.

    PYTHONPATH=src python benchmarks/side_by_side.py [--rounds 5] [--frames 20] [--threads 2]

1. ``passes``: two 384x640 inputs (and two 288x640 band tiles), run one after another on one
   session with ``--threads`` intra-op threads, and side by side on ``--threads`` one-thread
   sessions (``OnnxPose.infer_many``): ms per pass, alternated ``--rounds`` times.
2. ``modes``: ``far`` and ``stream`` on the 1600x900 street frame that ``pedenv bench`` times
   (level camera 1.5 m up; ``stream`` after its cold start: the whole frame, then two band
   tiles a frame), and ``stream`` on the real MOT17-04 sample frames (a crowd: the whole frame,
   then two packed inputs a frame) from ``../shared/samples/real``: ms per frame with each
   setting, alternated frame by frame, and whether both find the same persons (boxes to 1e-3 px).

Timings depend on the load, printed with each line; only the ratios within one line count.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

REAL = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"


def passes(rounds: int, threads: int) -> None:
    """Part 1 of the module doc."""
    from pedenv.detection import create_detector

    side = create_detector("onnx", detection="fast", threads=threads)
    alone = create_detector("onnx", detection="fast", threads=threads, side_by_side=False)
    rng = np.random.default_rng(0)
    for shape in ((1, 3, 384, 640), (1, 3, 288, 640)):
        tensors = [rng.random(shape, dtype=np.float32) for _ in range(2)]
        side.infer_many(tensors), [alone.infer(t) for t in tensors]  # warm up, sessions made
        times: dict[str, list[float]] = {"one after another": [], "side by side": []}
        for _ in range(rounds):
            for name in times:
                start = time.perf_counter()
                for _ in range(5):
                    if name == "side by side":
                        side.infer_many(tensors)
                    else:
                        [alone.infer(t) for t in tensors]
                times[name].append(1e3 * (time.perf_counter() - start) / 10)
        a, b = (float(np.median(v)) for v in times.values())
        print(f"{shape[2]}x{shape[3]}, two passes: one after another {a:.1f} ms a pass, side by side {b:.1f} "
              f"({a / b:.2f}x); load {os.getloadavg()[0]:.1f}", flush=True)


def frames_of(name: str, count: int) -> list[tuple[np.ndarray, object]]:
    """``count`` frames (image, geometry) of the benchmark frame or a MOT17 sample sequence."""
    from pedenv.detection.geometry import CameraGeometry
    from pedenv.images import read_image_rgb
    from pedenv.pose.timing import benchmark_image
    from pedenv.records import Camera

    if name == "street":
        geometry = CameraGeometry.level(Camera.from_fov().intrinsics, 1.5)
        return [(benchmark_image(), geometry)] * count
    paths = sorted((REAL / "mot17" / name / "img1").glob("*.jpg"))
    return [(read_image_rgb(paths[i % len(paths)]), None) for i in range(count)]


def modes(frames: int, threads: int) -> None:
    """Part 2 of the module doc."""
    from pedenv.detection import create_detector

    for mode, scene in (("far", "street"), ("stream", "street"), ("stream", "MOT17-04-FRCNN")):
        pose = {side: create_detector("onnx", detection=mode, threads=threads, side_by_side=side)
                for side in (True, False)}
        times: dict[bool, list[float]] = {True: [], False: []}
        same, runs = True, []
        for i, (image, geometry) in enumerate(frames_of(scene, frames + 1)):
            found = {}
            for side in ((True, False) if i % 2 else (False, True)):
                p = pose[side]
                start = time.perf_counter()
                found[side] = (p.detect_frame(image, geometry, 0.1 * i) if mode == "stream"
                               else p.detect(image, geometry))
                if i:  # the first frame (sessions made; stream's cold start) is not timed
                    times[side].append(1e3 * (time.perf_counter() - start))
            same &= len(found[True]) == len(found[False]) and bool(
                np.allclose(found[True].boxes, found[False].boxes, rtol=0, atol=1e-3))
            runs.append(len(pose[True].last_passes))
        on, off = (float(np.mean(times[s])) for s in (True, False))
        print(f"{mode} on {scene}, {frames} frames after the first, {np.mean(runs[1:]):.2f} passes a frame: "
              f"one after another {off:.1f} ms a frame, side by side {on:.1f} ({off / on:.2f}x); same persons: "
              f"{'yes' if same else 'NO'}; load {os.getloadavg()[0]:.1f}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=20)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    print(f"load {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores, {args.threads} threads", flush=True)
    passes(args.rounds, args.threads)
    modes(args.frames, args.threads)


if __name__ == "__main__":
    main()
