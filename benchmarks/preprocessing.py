"""Where the main thread's time beside the pose network goes, and the input conversion's cost.

    PYTHONPATH=src python benchmarks/preprocessing.py [--calls 300] [--frames 100] [--rounds 2]

1. Per call, on real images (a 1600x900 nuScenes frame, a 1242x375 KITTI frame) at two input
   sizes: letterbox, :func:`~pedenv.pose.postprocess.to_input_tensor` and its plain reference
   ``to_input_tensor_plain`` (alternated call by call, the order swapped every call), decode;
   main-thread CPU (``time.thread_time``) per call. The two conversions must agree bit for bit.
2. The loop of ``benchmarks/run_pipeline.py``'s "network alone" (read, detect with the fused
   preset's re-detection crops, ``model.update``; ``--detection fast``, vtest.avi at 1600x900),
   step by step: wall and main-thread CPU per frame of reading, detection beside the network
   (letterbox, tensor, decode and the rest) and the model's update.
Timings depend on the load: it is printed.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from collections import defaultdict
from dataclasses import replace
from functools import partial
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import run_pipeline  # noqa: E402  (the recording and the loop it measures)

REAL = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"
IMAGES = {"1600x900": REAL / "nuscenes-0061" / "n015-2018-07-24-11-22-45+0800__CAM_BACK__1532402927637525.jpg",
          "1242x375": REAL / "kitti" / "tracking_mini" / "training" / "image_02" / "0016" / "000002.png"}


def per_call(calls: int) -> None:
    """Part 1 of the module doc."""
    from pedenv.detection import create_detector
    from pedenv.images import read_image_rgb
    from pedenv.pose import postprocess as pp

    backend = create_detector("onnx", detection="fast", threads=2)
    for name, path in IMAGES.items():
        image = read_image_rgb(path)
        for size in [(384, 640), (224, 640)]:
            padded, box = pp.letterbox(image, size)
            assert np.array_equal(pp.to_input_tensor(padded), pp.to_input_tensor_plain(padded))
            out = backend.infer(pp.to_input_tensor(padded))
            steps = {"letterbox": partial(pp.letterbox, image, size), "tensor": partial(pp.to_input_tensor, padded),
                     "tensor plain": partial(pp.to_input_tensor_plain, padded), "decode": partial(pp.decode, out, box)}
            cpu = dict.fromkeys(steps, 0.0)
            for i in range(calls):
                for key in (list(steps) if i % 2 else list(steps)[::-1]):
                    start = time.thread_time()
                    steps[key]()
                    cpu[key] += time.thread_time() - start
            print(f"{name} -> {size[0]}x{size[1]}: " + ", ".join(f"{k} {1e3 * v / calls:.3f}" for k, v in cpu.items())
                  + f" ms CPU per call; load {os.getloadavg()[0]:.1f}", flush=True)


def in_the_loop(frames: int, rounds: int) -> None:
    """Part 2 of the module doc."""
    import pedenv.detection.passes as multipass
    from pedenv.config import Config
    from pedenv.detection import create_detector
    from pedenv.model import PedestrianEnvironmentModel
    from pedenv.recordings.footage import load_recording

    wall: dict[str, float] = defaultdict(float)
    cpu: dict[str, float] = defaultdict(float)

    def clocked(key, f):
        def timed(*args, **kwargs):
            w, c = time.perf_counter(), time.thread_time()
            try:
                return f(*args, **kwargs)
            finally:
                wall[key] += time.perf_counter() - w
                cpu[key] += time.thread_time() - c
        return timed

    for name in ("letterbox", "to_input_tensor", "decode"):
        setattr(multipass, name, clocked(name, getattr(multipass, name)))
    work = Path(tempfile.mkdtemp())
    rec = run_pipeline.write_recording(run_pipeline.VTEST, work, frames, (900, 1600))
    backend = create_detector("onnx", detection="fast", score_threshold=Config().tracking.pose_score_threshold,
                              threads=2, redetect=Config().redetect)
    backend.network.infer = clocked("network", backend.network.infer)
    for r in range(rounds + 1):  # the first warms up
        wall.clear()
        cpu.clear()
        cfg, load = Config(), os.getloadavg()[0]
        model = PedestrianEnvironmentModel(cfg)
        frames_in = iter(load_recording(**rec).frames())
        read = clocked("read frame", partial(next, frames_in, None))
        detect = clocked("detect", lambda frame, model=model: backend(frame, model.predict_tracks(frame)))
        update = clocked("model.update", model.update)
        n, start = 0, time.perf_counter()
        while (frame := read()) is not None:
            update(replace(frame, detections=detect(frame)))
            n += 1
        if r == 0:
            continue
        ms = {k: (1e3 * wall[k] / n, 1e3 * cpu[k] / n) for k in wall}
        ms["detect beside the network"] = (ms["detect"][0] - ms["network"][0], ms["detect"][1] - ms["network"][1])
        print(f"round {r}, load {load:.1f}-{os.getloadavg()[0]:.1f}: loop {1e3 * (time.perf_counter() - start) / n:.1f}"
              f" ms per frame, {backend.network_runs / n / (r + 1):.2f} passes; ms per frame (wall / main-thread CPU): "
              + ", ".join(f"{k} {w:.2f} / {c:.2f}" for k, (w, c) in ms.items() if k != "detect"), flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    per_call(args.calls)
    in_the_loop(args.frames, args.rounds)


if __name__ == "__main__":
    main()
