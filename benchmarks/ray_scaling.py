"""Serial against Ray: frames per second of an evaluation and of runs over several recordings.

    python benchmarks/ray_scaling.py                 # both comparisons, 2 Ray workers
    python benchmarks/ray_scaling.py --only builtin  # the built-in scenes alone
    python benchmarks/ray_scaling.py --only real --frames 16

* ``builtin``: the 7 built-in synthetic scenes (seed 0) with the detector model, evaluated
  serially (``run_evaluation``) and on a local Ray with ``--workers`` workers (one task per
  scene); also checks that both ``metrics.json`` are identical but for the stage timings.
* ``real``: 4 recordings made from real MOTChallenge frames (``../shared/samples/real/mot17``,
  read in place; 1920x1080 sequences MOT17-02, -04, -09, -13, each played forwards and
  backwards up to ``--frames`` frames, with a made-up calibration and a standing ego) written
  to a temporary folder outside the repository, run with the ONNX pose network through
  ``run_manifest`` serially and on Ray. Needs ``pedenv models prepare``.

Frames per second count every frame over the wall time of the whole call, Ray's start
and its workers' first imports included ("ray fps"); "warm ray fps" is a second
evaluation on the same Ray (workers running, pedenv imported), the steady state of a long
run. Run it on an idle machine: the figures are wall times.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

MOT17 = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real" / "mot17"
SEQUENCES = ("MOT17-02-FRCNN", "MOT17-04-FRCNN", "MOT17-09-FRCNN", "MOT17-13-FRCNN")
CALIBRATION = """width: 1920
height: 1080
intrinsics: [[1660.0, 0, 960.0], [0, 1660.0, 540.0], [0, 0, 1]]
cam_to_vehicle:
  rotation: [0.5, -0.5, 0.5, -0.5]
  translation: [0.0, 0.0, 1.5]
"""


def bench_builtin(workers: int) -> dict:
    from pedenv.apps.demo import builtin_scenes
    from pedenv.apps.distributed import evaluate_on
    from pedenv.apps.evaluate import run_evaluation
    from pedenv.apps.executors import RayExecutor
    from pedenv.datasets.memory import MemoryDataset

    data = MemoryDataset(builtin_scenes(0), name="synthetic", default_pose_backend="detector-model")
    frames = sum(len(list(data.frames(n))) for n in data.scene_names())
    t0 = time.perf_counter()
    serial = run_evaluation(data).metrics.to_dict()
    t_serial = time.perf_counter() - t0
    t0 = time.perf_counter()
    with RayExecutor(workers=workers, object_store_memory=500 * 1024**2) as ex:
        t_start = time.perf_counter() - t0
        ray = evaluate_on(data, executor=ex).metrics.to_dict()
        t_ray = time.perf_counter() - t0
        t1 = time.perf_counter()  # again on the same Ray: workers started, pedenv imported (a long run's steady state)
        warm = evaluate_on(data, executor=ex).metrics.to_dict()
        t_warm = time.perf_counter() - t1
    strip = lambda m: {k: v for k, v in m.items() if k != "timing_ms"}  # noqa: E731
    same = strip(serial) == strip(ray) == strip(warm)
    return {"case": "built-in scenes, detector model", "frames": frames, "serial_s": t_serial, "ray_s": t_ray,
            "ray_start_s": t_start, "warm_s": t_warm, "metrics_identical": same}


def make_recordings(root: Path, frames: int) -> Path:
    """4 recordings of real MOT17 frames in the footage formats, and their manifest; returns the manifest."""
    (root / "calibration.yaml").write_text(CALIBRATION)
    rows = ["name,images,calibration,ego_poses,fps"]
    for seq in SEQUENCES:
        images = sorted((MOT17 / seq / "img1").glob("*.jpg"))
        cycle = images + images[-2:0:-1]  # forwards then backwards: a longer clip of real frames
        folder = root / seq / "images"
        folder.mkdir(parents=True)
        for i in range(frames):
            os.symlink(cycle[i % len(cycle)], folder / f"{i:06d}.jpg")
        (root / seq / "poses.csv").write_text("timestamp,x,y,yaw\n0,0,0,0\n1000,0,0,0\n")
        rows.append(f"{seq},{seq}/images,calibration.yaml,{seq}/poses.csv,30")
    manifest = root / "manifest.csv"
    manifest.write_text("\n".join(rows) + "\n")
    return manifest


def bench_real(workers: int, frames: int) -> dict:
    from pedenv.apps.batch import run_manifest
    from pedenv.apps.options import ExecutorOptions

    root = Path(tempfile.mkdtemp(prefix="pedenv-ray-bench-"))
    try:
        manifest = make_recordings(root, frames)
        times = {}
        for executor in ("serial", "ray"):
            t0 = time.perf_counter()
            ray = executor == "ray"
            options = ExecutorOptions(executor, workers=workers if ray else None,
                                      object_store_memory=500 * 1024**2 if ray else None)
            summary = run_manifest(manifest, root / f"out-{executor}", executor=options)
            times[executor] = time.perf_counter() - t0
            if summary["failed"]:
                raise SystemExit(json.dumps(summary["recordings"], indent=2))
        same = all((root / "out-serial" / s / "environment.jsonl").read_bytes()
                   == (root / "out-ray" / s / "environment.jsonl").read_bytes() for s in SEQUENCES)
        return {"case": f"4 real MOT17 recordings x {frames} frames, ONNX pose", "frames": 4 * frames,
                "serial_s": times["serial"], "ray_s": times["ray"], "ray_start_s": None, "warm_s": None,
                "metrics_identical": same}
    finally:
        shutil.rmtree(root, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", choices=("builtin", "real"))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--frames", type=int, default=24, help="frames per real recording")
    args = parser.parse_args()
    rows = []
    if args.only in (None, "builtin"):
        rows.append(bench_builtin(args.workers))
    if args.only in (None, "real"):
        rows.append(bench_real(args.workers, args.frames))
    load = os.getloadavg()
    print(f"cores: {os.cpu_count()}, load average before the last case: {load[0]:.2f} (1 min)")
    print(f"{'case':48} {'frames':>6} {'serial fps':>10} {'ray fps':>8} {'speed-up':>8} {'ray start s':>11} "
          f"{'warm ray fps':>12} {'warm speed-up':>13}  same")
    for r in rows:
        start = f"{r['ray_start_s']:.1f}" if r["ray_start_s"] is not None else "in ray fps"
        warm = (f"{r['frames'] / r['warm_s']:12.1f} {r['serial_s'] / r['warm_s']:13.2f}" if r["warm_s"]
                else f"{'-':>12} {'-':>13}")
        print(f"{r['case']:48} {r['frames']:6d} {r['frames'] / r['serial_s']:10.1f} {r['frames'] / r['ray_s']:8.1f} "
              f"{r['serial_s'] / r['ray_s']:8.2f} {start:>11} {warm}  {r['metrics_identical']}")


if __name__ == "__main__":
    main()
