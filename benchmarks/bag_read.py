"""What reading a ROS bag costs next to the whole run, per frame (goal: at most 10 %).

    python benchmarks/bag_read.py [--repeats 3] [--detection far]

Writes bags of the real samples with the tests' writer (``tests/recordings/bag_samples.py``):
KITTI tracking 0016 (1224x370) as raw rgb8 in rosbag2 MCAP, MOT17-09 (1920x1080) as its JPEG
files in a single .mcap and as raw rgb8 in rosbag2 sqlite3. For each it times reading the bag
(``load_bag_recording`` + every Frame: messages, decoding, ego interpolation) and
``pedenv run --bag`` on it (onnx pose network, the default model), and prints the milliseconds per
frame of both and their ratio. The best of ``--repeats`` of each; timings on a shared
machine vary, so both are taken in the same process, one after the other.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT.parent / "shared" / "samples" / "real"
sys.path.insert(0, str(ROOT / "tests" / "recordings"))


def _bags(folder: Path) -> dict[str, Path]:
    from bag_samples import BagForm, quaternion_calibration, write_bag

    from pedenv.recordings.footage_writer import write_kitti_recording, write_mot17_recording

    kitti = write_kitti_recording(SAMPLES / "kitti" / "tracking_mini" / "training", "0016", folder / "kitti")
    mot = write_mot17_recording(SAMPLES / "mot17" / "MOT17-09-FRCNN", folder / "mot17", pitch_down_deg=10.0)
    for rec in (kitti, mot):
        quaternion_calibration(rec)
    return {"KITTI 0016 raw rgb8, rosbag2 MCAP": write_bag(kitti, folder / "kitti-mcap", BagForm("mcap", "rgb8")),
            "MOT17-09 JPEG, single .mcap": write_bag(mot, folder / "mot.mcap", BagForm("mcap-file", "compressed")),
            "MOT17-09 raw rgb8, rosbag2 sqlite3": write_bag(mot, folder / "mot-sqlite", BagForm("sqlite3", "rgb8"))}


def _read(bag: Path) -> tuple[float, int]:
    from pedenv.recordings.bag import load_bag_recording

    start = time.perf_counter()
    n = sum(1 for _ in load_bag_recording(bag).frames())
    return time.perf_counter() - start, n


def _run(bag: Path, out: Path, backend) -> tuple[float, int]:
    from pedenv.apps.run import run_recording

    start = time.perf_counter()
    summary = run_recording(bag=bag, output=out, overwrite=True, backend=backend)
    return time.perf_counter() - start, summary["frames_done"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--detection", default="far", choices=("far", "fast"))
    args = parser.parse_args()
    os.environ.setdefault("YOLO_OFFLINE", "1")
    from pedenv.pose.base import create_pose_backend

    backend = create_pose_backend("onnx", detection=args.detection)
    print(f"load: {os.getloadavg()[0]:.1f} (1 min), {os.cpu_count()} CPUs; detection {args.detection}")
    print(f"{'bag':<36} {'frames':>6} {'read ms/frame':>14} {'run ms/frame':>13} {'read/run':>9}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, bag in _bags(Path(tmp)).items():
            read = min(_read(bag)[0] for _ in range(args.repeats))
            runs = [_run(bag, Path(tmp) / "out", backend) for _ in range(args.repeats)]
            run, frames = min(r[0] for r in runs), runs[0][1]
            print(f"{name:<36} {frames:>6} {1e3 * read / frames:>14.1f} {1e3 * run / frames:>13.1f} "
                  f"{read / run:>8.1%}")


if __name__ == "__main__":
    main()
