"""What reading a ROS bag costs next to the whole run, per frame (goal: at most 10 %).

    python benchmarks/bag_read.py [--repeats 3] [--detection far]

Writes bags of the real samples with the tests' writer (``tests/recordings/bag_samples.py``):
KITTI tracking 0016 (1224x370) as raw rgb8 in rosbag2 MCAP, MOT17-09 (1920x1080) as its JPEG
files in a single .mcap and as raw rgb8 in rosbag2 sqlite3. For each it times reading the bag
(``load_bag_recording``: camera, tf, ego poses, once per bag; then every Frame: messages,
decoding, ego interpolation), the same frames from the image folder the bag was written from,
and ``pedenv run --bag`` on it (onnx pose network, the default model). Prints the opening in ms,
the rest in ms per frame, and read/run: (opening + frames) / the whole run. These bags are
short (3-4 frames), so the opening weighs more here than in a real bag. The best of
``--repeats`` of each; timings on a shared machine vary, so all are taken in one process.
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


def _bags(folder: Path) -> dict[str, tuple[Path, Path]]:
    """name -> (bag, the image-folder recording it was written from)."""
    from bag_samples import BagForm, quaternion_calibration, write_bag

    from pedenv.recordings.footage_writer import write_kitti_recording, write_mot17_recording

    kitti = write_kitti_recording(SAMPLES / "kitti" / "tracking_mini" / "training", "0016", folder / "kitti")
    mot = write_mot17_recording(SAMPLES / "mot17" / "MOT17-09-FRCNN", folder / "mot17", pitch_down_deg=10.0)
    for rec in (kitti, mot):
        quaternion_calibration(rec)
    return {"KITTI 0016 raw rgb8, rosbag2 MCAP": (write_bag(kitti, folder / "kitti-mcap", BagForm("mcap", "rgb8")),
                                                  kitti),
            "MOT17-09 JPEG, single .mcap": (write_bag(mot, folder / "mot.mcap", BagForm("mcap-file", "compressed")),
                                            mot),
            "MOT17-09 raw rgb8, rosbag2 sqlite3": (write_bag(mot, folder / "mot-sqlite", BagForm("sqlite3", "rgb8")),
                                                   mot)}


def _read(bag: Path) -> tuple[float, float, int]:
    """Seconds to open the bag (camera, tf, ego poses) and to read every Frame; the frame count."""
    from pedenv.recordings.bag import load_bag_recording

    start = time.perf_counter()
    rec = load_bag_recording(bag)
    opened = time.perf_counter()
    n = sum(1 for _ in rec.frames())
    return opened - start, time.perf_counter() - opened, n


def _folder(rec: Path) -> float:
    """Seconds to read the image-folder recording's Frames (what the bag replaces)."""
    from pedenv.recordings.footage import load_recording

    start = time.perf_counter()
    folder = load_recording(calibration=rec / "calibration.yaml", ego_poses=rec / "ego_poses.csv",
                            images=rec / "images")
    sum(1 for _ in folder.frames())
    return time.perf_counter() - start


def _run(bag: Path, out: Path, backend) -> tuple[float, int]:
    from pedenv.apps.options import OutputOptions, RecordingSource
    from pedenv.apps.run import run_recording

    start = time.perf_counter()
    summary = run_recording(RecordingSource(bag=bag), OutputOptions(out, overwrite=True), backend=backend)
    return time.perf_counter() - start, summary["frames_done"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--detection", default="far", choices=("far", "fast"))
    args = parser.parse_args()
    os.environ.setdefault("YOLO_OFFLINE", "1")
    from pedenv.detection import create_detector

    backend = create_detector("onnx", detection=args.detection)
    print(f"load: {os.getloadavg()[0]:.1f} (1 min), {os.cpu_count()} CPUs; detection {args.detection}")
    print(f"{'bag':<36} {'frames':>6} {'open ms':>8} {'frame ms':>9} {'folder ms':>10} {'run ms':>8} "
          f"{'read/run':>9}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, (bag, rec) in _bags(Path(tmp)).items():
            reads = [_read(bag) for _ in range(args.repeats)]
            opened, frames_s, frames = min(r[0] for r in reads), min(r[1] for r in reads), reads[0][2]
            folder = min(_folder(rec) for _ in range(args.repeats))
            run = min(_run(bag, Path(tmp) / "out", backend)[0] for _ in range(args.repeats))
            print(f"{name:<36} {frames:>6} {1e3 * opened:>8.1f} {1e3 * frames_s / frames:>9.1f} "
                  f"{1e3 * folder / frames:>10.1f} {1e3 * run / frames:>8.1f} {(opened + frames_s) / run:>8.1%}")

if __name__ == "__main__":
    main()
