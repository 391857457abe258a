"""Memory of the model over a long stream (issue 10: it must stay flat), and with ``--sinks DIR``
the growth of the per-frame outputs (issue 19: linear in the stream's length).

    PYTHONPATH=src python benchmarks/memory_stream.py --frames 20000 --method fused
    PYTHONPATH=src python benchmarks/memory_stream.py --frames 10000 --method fused --sinks sinks --every 1000

With ``--sinks`` every frame also goes to a Rerun recording (``DIR/stream.rrd``; its size is
printed, with the bytes added per frame since the last checkpoint) and the bird's-eye video
(``DIR/birds_eye.mp4``; the number of track trails it holds is printed).

A synthetic 10 Hz stream with jittered real-world timestamps (every interval distinct, as
from a real clock), 3 pedestrians walking in and out of view and a small false positive
now and then, through ``PedestrianEnvironmentModel.update``. Prints the process's resident
memory (``/proc/self/statm``) and the Python heap traced by ``tracemalloc`` at checkpoints,
and the size of the Kalman transition cache. Not a test: it prints figures.
"""

from __future__ import annotations

import argparse
import os
import tracemalloc
from pathlib import Path

import numpy as np

from pedenv.config import Config
from pedenv.geometry import invert_transform, project
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def stream(n_frames: int, seed: int = 0):
    rng = np.random.default_rng(seed)
    camera = Camera.from_fov()
    heights = np.array([.92, .94, .94, .93, .93, .82, .82, .62, .62, .48, .48, .53, .53, .29, .29, .05, .05])
    lateral = np.array([0, .03, -.03, .07, -.07, .2, -.2, .24, -.24, .25, -.25, .1, -.1, .1, -.1, .1, -.1])
    t = 0.0
    for i in range(n_frames):
        t += 0.1 + rng.uniform(-0.003, 0.003)
        ego = EgoPose.from_xy_yaw(5.0 * t, 0.0, 0.0)
        frame = Frame(i, t, camera, ego)
        phase = (t % 60.0) / 60.0
        people = [(5.0 * t + 8.0 + 30.0 * ((phase + k / 3) % 1.0), -3.0 + 3.0 * k) for k in range(3)]
        pts = np.stack([np.column_stack([np.full(17, x), y + lateral * 1.7, heights * 1.7]) for x, y in people])
        uv, depth = project(pts, camera.intrinsics, invert_transform(frame.cam_to_world))
        uv = uv + rng.normal(0, 1.5, uv.shape)
        keep = (depth > 0).all(axis=1) & (uv[..., 0] > 0).all(axis=1) & (uv[..., 0] < 1600).all(axis=1)
        kp, conf = uv[keep], np.full((int(keep.sum()), 17), 0.9)
        if rng.random() < 0.05:  # a tiny false positive
            fp = rng.uniform([100, 300], [1500, 500]) + rng.normal(0, 1.0, (1, 17, 2))
            kp, conf = np.concatenate([kp, fp]), np.concatenate([conf, np.full((1, 17), 0.4)])
        yield Frame(i, t, camera, ego, detections=Detections(kp.reshape(-1, 17, 2), conf.reshape(-1, 17)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20000)
    parser.add_argument("--method", default="paper", choices=["paper", "fused"])
    parser.add_argument("--sinks", type=Path, default=None, help="Also write a .rrd and the bird's-eye video here.")
    parser.add_argument("--every", type=int, default=None, help="Print every N frames (default 1000, 5000, 10000).")
    args = parser.parse_args()
    model = PedestrianEnvironmentModel(configure(Config(), args.method))
    checkpoints = set(range(args.every, args.frames + 1, args.every)) if args.every else {1000, 5000, 10000}
    checkpoints.add(args.frames)
    sinks = _open_sinks(args.sinks) if args.sinks else None
    tracemalloc.start()
    far, rrd_before, frames_before = 0.0, 0, 0
    for frame in stream(args.frames):
        state = model.update(frame)
        if sinks is not None:
            for sink in sinks:
                sink.write(state, frame)
        far = max(far, float(state.pedestrians.distances.max(initial=0.0)))
        if frame.index + 1 in checkpoints:
            current, peak = tracemalloc.get_traced_memory()
            line = (f"{args.method} frame {frame.index + 1:6d}: RSS {rss_mb():7.1f} MB, "
                    f"traced heap {current / 2**20:6.2f} MB (peak {peak / 2**20:6.2f}), tracks {len(model.tracks)}, "
                    f"transition cache {model._transition.cache_info().currsize}, farthest distance so far {far:.1f} m")
            if sinks is not None:
                rrd = (args.sinks / "stream.rrd").stat().st_size
                per_frame = (rrd - rrd_before) / (frame.index + 1 - frames_before)
                line += (f"; .rrd {rrd / 2**20:8.2f} MB (+{per_frame / 1024:6.2f} KB/frame since the last line), "
                         f"bird's-eye trails held {len(sinks[1]._trails)}")
                rrd_before, frames_before = rrd, frame.index + 1
            print(line, flush=True)
    for sink in sinks or []:
        sink.close()


def _open_sinks(folder: Path) -> list:
    from pedenv.outputs.rerun_log import RerunWriter
    from pedenv.visualize.birds_eye_video import BirdsEyeVideo

    folder.mkdir(parents=True, exist_ok=True)
    for old in (folder / "stream.rrd", folder / "birds_eye.mp4"):
        old.unlink(missing_ok=True)
    return [RerunWriter(folder / "stream.rrd"), BirdsEyeVideo(folder / "birds_eye.mp4")]


if __name__ == "__main__":
    main()
