"""Visual odometry against GPS/IMU on real KITTI frames, and on a static camera.

Prints, per real sequence, the distance travelled and the yaw change from the images
(:class:`pedenv.odometry.estimator.VisualOdometry`) beside KITTI's OXTS GPS/IMU (positions by
the devkit's Mercator projection), and for a static video the motion estimated over all of it;
then the ``--static`` check on real fixed and moving cameras (KITTI raw, MOT17, the video).

Usage::

    python benchmarks/visual_odometry.py [--kitti ../shared/samples/real/kitti]
        [--video /usr/share/doc/opencv-doc/examples/data/vtest.avi]

The video is Debian's ``opencv-doc`` ``examples/data/vtest.avi`` (a fixed camera over a plaza);
its camera is not known, so a plausible one is assumed (it cannot matter: a static camera's
tracks do not move).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import cv2
import numpy as np

from pedenv.datasets.kitti_files import read_calib
from pedenv.errors import InputError
from pedenv.geometry import rotation_from_ypr
from pedenv.images import read_image_rgb
from pedenv.odometry.estimator import VisualOdometry
from pedenv.odometry.reference import integrated_distance, mercator_positions, read_oxts, travelled, yaw_change
from pedenv.odometry.stream import OdometryStream

#: KITTI's colour camera is about 1.65 m above the road, looking straight ahead (KITTI's setup page).
KITTI_CAMERA_HEIGHT_M = 1.65
#: Optical camera axes -> vehicle axes of a camera looking straight ahead.
FORWARD = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def mounting(height_m: float, pitch_down_deg: float = 0.0) -> np.ndarray:
    """(4, 4) camera -> vehicle of a camera ``height_m`` above the road, pitched down by ``pitch_down_deg``."""
    t = np.eye(4)
    t[:3, :3] = rotation_from_ypr(0.0, np.radians(pitch_down_deg), 0.0) @ FORWARD
    t[2, 3] = height_m
    return t


def measure_or_say(images: list[Path], stamps: np.ndarray, k: np.ndarray, oxts: np.ndarray, oxts_times: np.ndarray,
                   name: str) -> None:
    """:func:`measure`, or the one line saying why the odometry could not run."""
    try:
        measure(images, stamps, k, oxts, oxts_times, name)
    except InputError as exc:
        print(f"{name}: not measured: {exc}")


def measure(images: list[Path], stamps: np.ndarray, k: np.ndarray, oxts: np.ndarray, oxts_times: np.ndarray,
            name: str) -> None:
    """Print the odometry of ``images`` at ``stamps`` (seconds) against ``oxts`` (the rows spanning them,
    at ``oxts_times`` seconds): the GPS positions' path and the speed integrated; then the poses of
    ``pedenv run``'s frame loop (:class:`~pedenv.odometry.stream.OdometryStream`)."""
    vo = VisualOdometry(k, mounting(KITTI_CAMERA_HEIGHT_M))
    start, cpu = time.perf_counter(), time.process_time()
    for path, stamp in zip(images, stamps):
        vo.update(read_image_rgb(path), float(stamp), where=str(path))  # as pedenv run reads them
    per_step = (time.perf_counter() - start) / max(len(images) - 1, 1)
    cpu_step = (time.process_time() - cpu) / max(len(images) - 1, 1)
    poses = vo.poses()
    distance, truth = travelled(poses[:, :3, 3]), travelled(mercator_positions(oxts))
    speed = integrated_distance(oxts, oxts_times)
    yaw = np.degrees(np.arctan2(poses[-1, 1, 0], poses[-1, 0, 0]))
    truth_yaw = np.degrees(yaw_change(oxts))
    print(f"{name}: {len(images)} frames, distance {distance:.3f} m vs GPS positions {truth:.3f} m "
          f"({100 * (distance / truth - 1):+.2f} %) and integrated speed {speed:.3f} m "
          f"({100 * (distance / speed - 1):+.2f} %), yaw change {yaw:+.3f} deg vs {truth_yaw:+.3f} deg "
          f"(error {yaw - truth_yaw:+.3f} deg); {len(vo.steps)} steps, {sum(s.guided for s in vo.steps)} scaled by "
          f"aligning the road, {sum(s.wide for s in vo.steps)} from matched descriptors; {1e3 * per_step:.0f} ms "
          f"per frame ({1e3 * cpu_step:.0f} ms of CPU, the image's decoding included)")
    stream, handed = OdometryStream(k, mounting(KITTI_CAMERA_HEIGHT_M)), []
    for path, stamp in zip(images, stamps):  # pedenv run's frame loop: each pose final POSE_LAG_FRAMES later
        handed += stream.add(read_image_rgb(path), float(stamp), where=str(path))
    looped = np.array(handed + stream.finish())
    loop_yaw = np.degrees(np.arctan2(looped[-1, 1, 0], looped[-1, 0, 0]))
    print(f"{name}, pedenv run's frame loop (poses final {stream.lag} frames later): distance "
          f"{travelled(looped[:, :3, 3]):.3f} m ({100 * (travelled(looped[:, :3, 3]) / truth - 1):+.2f} % of the GPS "
          f"positions'), yaw error {loop_yaw - truth_yaw:+.3f} deg, at most "
          f"{np.abs(looped[:, :3, 3] - poses[:, :3, 3]).max():.3f} m from the whole recording's poses"
          if len(looped) == len(poses) else f"{name}, frame loop: {len(looped)} poses")


def kitti_raw(root: Path) -> None:
    drive = root / "raw_2011_09_26_drive_0002"
    sync = drive / "2011_09_26_drive_0002_sync"
    line = next(t for t in (drive / "calib_cam_to_cam.txt").read_text().splitlines() if t.startswith("P_rect_02:"))
    k = np.array(line.split()[1:], dtype=np.float64).reshape(3, 4)[:, :3]
    stamps = np.array([np.datetime64(t.strip()) for t in (sync / "image_02/timestamps.txt").read_text().split("\n")
                       if t.strip()])
    images = sorted((sync / "image_02/data").glob("*.png"))  # the first frames of the drive's timestamps
    seconds = ((stamps - stamps[0]) / np.timedelta64(1, "ns") * 1e-9)[:len(images)]
    oxts = read_oxts(sorted((sync / "oxts/data").glob("*.txt")))
    measure_or_say(images, seconds, k, oxts, seconds, "kitti raw 2011_09_26_0002")  # OXTS synced to the images


def kitti_tracking(folder: Path, frames: list[int], name: str, oxts_file: Path) -> None:
    training = folder / "training"
    k = read_calib(training / "calib/0001.txt").K
    oxts = read_oxts(oxts_file)[frames[0]:frames[-1] + 1]
    images = [training / f"image_02/0001/{f:06d}.png" for f in frames]
    measure_or_say(images, np.array(frames) / 10.0, k, oxts, frames[0] / 10.0 + np.arange(len(oxts)) / 10.0, name)


def static_video(video: Path) -> None:
    """The motion estimated over the whole of a fixed camera's video (assumed camera: 7 m up, 30 deg down)."""
    cap = cv2.VideoCapture(str(video))
    rate = cap.get(cv2.CAP_PROP_FPS) or 10.0
    width, height = cap.get(cv2.CAP_PROP_FRAME_WIDTH), cap.get(cv2.CAP_PROP_FRAME_HEIGHT)
    k = np.array([[width, 0.0, width / 2], [0.0, width, height / 2], [0.0, 0.0, 1.0]])
    vo = VisualOdometry(k, mounting(7.0, 30.0))
    index, start = 0, time.perf_counter()
    while True:
        ok, bgr = cap.read()
        if not ok:
            break
        vo.update(cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY), index / rate, where=f"{video}#{index}")
        index += 1
    poses = vo.poses()
    moved = np.linalg.norm(poses[:, :3, 3] - poses[0, :3, 3], axis=1)
    yaw = np.degrees(np.arctan2(poses[:, 1, 0], poses[:, 0, 0]))
    print(f"static {video.name}: {index} frames, largest distance from the start {moved.max():.4f} m, path "
          f"{travelled(poses[:, :3, 3]):.4f} m, largest yaw {np.abs(yaw).max():.3f} deg, "
          f"{len(vo.key_timestamps)} keyframe(s) (a new one where the image changed measurably), "
          f"{1e3 * (time.perf_counter() - start) / max(index, 1):.0f} ms per frame")


def static_checks(root: Path, video: Path | None) -> None:
    """The check of a camera declared ``--static`` (:func:`pedenv.odometry.static_check.check_static`) on
    real fixed and moving cameras: the largest median flow of its frame pairs, and whether it refuses."""
    from pedenv.odometry.static_check import check_static

    folders = [root / "kitti/raw_2011_09_26_drive_0002/2011_09_26_drive_0002_sync/image_02/data",
               *sorted((root / "mot17").glob("MOT17-*/img1"))]
    for kind, source in [("images", f) for f in folders] + ([("video", video)] if video is not None else []):
        try:
            flows = check_static(**{kind: source})
            print(f"static check {source}: passes, largest median flow of {len(flows)} frame pairs "
                  f"{max((f for _, f in flows), default=0.0):.3f} px")
        except InputError as exc:
            print(f"static check: refused: {exc}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kitti", type=Path, default=Path("../shared/samples/real/kitti"))
    parser.add_argument("--real", type=Path, default=Path("../shared/samples/real"),
                        help="the real samples (KITTI raw and MOT17 for the --static check)")
    parser.add_argument("--video", type=Path, default=None, help="a static camera's video (vtest.avi)")
    args = parser.parse_args()
    kitti_raw(args.kitti)
    sequences = args.kitti / "tracking_sequences"
    oxts = sequences / "training/oxts/0001.txt"
    kitti_tracking(sequences, [0, 1], "kitti tracking_sequences 0001 frames 0-1", oxts)
    kitti_tracking(args.kitti / "tracking_mini", [10, 15, 20], "kitti tracking_mini 0001 frames 10, 15, 20", oxts)
    if args.video is not None:
        static_video(args.video)
    static_checks(args.real, args.video)


if __name__ == "__main__":
    main()
