"""Visual odometry against GPS/IMU on real KITTI frames, and on a static camera.

Prints, per real sequence, the distance travelled and the yaw change from the images
(:class:`pedenv.odometry.estimator.VisualOdometry`) beside KITTI's OXTS GPS/IMU (positions by
the devkit's Mercator projection), and for a static video the motion estimated over all of it;
then the ``--static`` check on real fixed and moving cameras (KITTI raw, MOT17, the video).
``--only cost``: what the estimation adds to ``pedenv run``'s time per frame (:func:`cost`); ``--only parts``:
where a frame's estimation goes (:func:`parts`).

Usage::

    python benchmarks/visual_odometry.py [--kitti ../shared/samples/real/kitti]
        [--video /usr/share/doc/opencv-doc/examples/data/vtest.avi] [--only kitti|static|cost|parts] [--runs 4]

The video is Debian's ``opencv-doc`` ``examples/data/vtest.avi`` (a fixed camera over a plaza);
its camera is not known, so a plausible one is assumed (it cannot matter: a static camera's
tracks do not move).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np

from pedenv.datasets.kitti_files import read_calib
from pedenv.errors import InputError
from pedenv.geometry import rotation_from_ypr, rotation_to_quaternion
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


def _fastest_ms(call: Callable[[], object], repeats: int = 15) -> float:
    """The fastest of ``repeats`` calls of ``call``, ms of this thread's CPU."""
    times = []
    for _ in range(repeats):
        start = time.thread_time()
        call()
        times.append(time.thread_time() - start)
    return 1e3 * min(times)


def parts(root: Path) -> None:
    """Where a step's estimation goes: each part of :func:`~pedenv.odometry.motion.estimate_step` timed alone on
    KITTI raw 0002 frames 3-4 (one OpenCV thread, the fastest of 15), then the whole step and
    :class:`~pedenv.odometry.stream.OdometryStream` over the 10 frames (CPU a frame)."""
    from pedenv.odometry import features, ground, motion

    cv2.setNumThreads(1)
    drive = root / "raw_2011_09_26_drive_0002"
    line = next(t for t in (drive / "calib_cam_to_cam.txt").read_text().splitlines() if t.startswith("P_rect_02:"))
    k = np.ascontiguousarray(np.array(line.split()[1:], dtype=np.float64).reshape(3, 4)[:, :3])
    mount = mounting(KITTI_CAMERA_HEIGHT_M)
    images = [read_image_rgb(p) for p in sorted((drive / "2011_09_26_drive_0002_sync/image_02/data").glob("*.png"))]
    gray0, gray1 = (cv2.cvtColor(images[i], cv2.COLOR_RGB2GRAY) for i in (3, 4))
    allowed = features.person_mask(gray0.shape, None)
    road_mask = allowed & ground.road_mask(gray0.shape, k, mount)
    corners, rank = features.ranked_corners(gray0, allowed)
    first = int((rank < motion.FIRST_PASS_PER_CELL).sum())
    road_corners = features.detect_road_corners(gray0, road_mask)
    p0, p1, _ = motion._tracks(gray0, gray1, corners, first, road_corners)
    count, rotation, direction, inlier = motion._essential(p0, p1, k)
    road = inlier & ground.on_road(p0, k, mount)
    down = ground.camera_down(mount)
    timed = {
        "FAST corners": lambda: features.ranked_corners(gray0, allowed),
        "road corners (Shi-Tomasi)": lambda: features.detect_road_corners(gray0, road_mask),
        f"road corners' flow ({len(road_corners)})": lambda: features.track(gray0, gray1, road_corners),
        f"FAST corners' flow ({first})": lambda: features.track_half(gray0, gray1, corners[:first]),
        f"essential matrix ({len(p0)} tracks)": lambda: motion._essential(p0, p1, k),
        f"road plane fit ({int(road.sum())} tracks)": lambda: ground.fit_road(p0[road], p1[road], k, rotation,
                                                                               direction, down),
        "whole step": lambda: motion.estimate_step(gray0, gray1, k, mount),
    }
    print("parts, KITTI raw 0002 frames 3-4, ms of CPU (one OpenCV thread, fastest of 15): " + ", ".join(
        f"{name} {_fastest_ms(call):.1f}" for name, call in timed.items()))
    stream = OdometryStream(k, mount)
    for i, image in enumerate(images):
        stream.add(image, 0.1 * i)
    print(f"parts: OdometryStream over the 10 frames {1e3 * stream.spent[1] / len(images):.1f} ms of CPU a frame "
          f"(one OpenCV thread)")


#: The cost's recording: KITTI raw 0002's 10 frames played forward and back (0..9, 8..0, 1..9, ...), each
#: step a real step of about 0.9 m, to this many frames.
COST_FRAMES = 54
#: Frames left out of the cost's per-frame time at the start of a run (the network's warm-up, the first
#: poses waiting for the lag).
COST_WARMUP_FRAMES = 5


def _cost_recording(root: Path, folder: Path) -> tuple[Path, Path]:
    """An image folder of links to raw 0002's frames played forward and back (:data:`COST_FRAMES`) and a
    calibration YAML (the drive's intrinsics, the camera 1.65 m up looking straight ahead) under ``folder``."""
    drive = root / "raw_2011_09_26_drive_0002"
    frames = sorted((drive / "2011_09_26_drive_0002_sync/image_02/data").glob("*.png"))
    order = [*range(len(frames)), *range(len(frames) - 2, 0, -1)]
    images = folder / "images"
    images.mkdir()
    for i in range(COST_FRAMES):
        os.symlink(frames[order[i % len(order)]].resolve(), images / f"{i:06d}.png")
    line = next(t for t in (drive / "calib_cam_to_cam.txt").read_text().splitlines() if t.startswith("P_rect_02:"))
    k = np.array(line.split()[1:], dtype=np.float64).reshape(3, 4)[:, :3]
    height, width = cv2.imread(str(frames[0]), cv2.IMREAD_GRAYSCALE).shape
    mount = mounting(KITTI_CAMERA_HEIGHT_M)
    calib = folder / "kitti.yaml"
    calib.write_text(json.dumps({"width": width, "height": height, "fx": k[0, 0], "fy": k[1, 1], "cx": k[0, 2],
                                 "cy": k[1, 2], "cam_to_vehicle": {
                                     "rotation": rotation_to_quaternion(mount[:3, :3]).tolist(),
                                     "translation": mount[:3, 3].tolist()}}))
    return images, calib


def _cost_run(images: Path, calib: Path, out: Path, ego_poses: Path | None) -> tuple[float, float, float, dict]:
    """One ``pedenv run --images images --calibration calib --fps 10 [--ego-poses ego_poses]`` into ``out``:
    (ms a frame of the frame loop, the same after :data:`COST_WARMUP_FRAMES`, ms of the process's CPU (all its
    threads) a frame, run.json's ``ego_poses``)."""
    from pedenv.apps.options import OutputOptions, RecordingSource
    from pedenv.apps.run import run_recording

    written: list[float] = []
    cpu = time.process_time()
    summary = run_recording(RecordingSource(images=images, calibration=calib, ego_poses=ego_poses, fps=10.0),
                            OutputOptions(out), progress=lambda *_: written.append(time.perf_counter()))
    cpu = time.process_time() - cpu
    frames, after = summary["frames_done"], np.diff(written[COST_WARMUP_FRAMES - 1:])
    wall = summary["speed"]["wall_s"]
    return 1e3 * wall / frames, 1e3 * float(after.mean()), 1e3 * cpu / frames, summary["ego_poses"]


def cost(root: Path, runs: int) -> None:
    """What the visual odometry adds to ``pedenv run``'s time a frame: :func:`_cost_recording`'s frames run with
    the poses estimated in the frame loop and with ``--ego-poses`` (the first run's estimate), alternated in
    this process ``runs`` times each; medians, and the estimation's CPU in the reader thread."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        images, calib = _cost_recording(root, folder)
        rows: dict[str, list[tuple[float, float, float]]] = {"estimated": [], "given": []}
        cpu: list[float] = []
        for i in range(runs):
            *times, poses = _cost_run(images, calib, folder / f"estimated{i}", None)
            rows["estimated"].append((times[0], times[1], times[2]))
            cpu.append(1e3 * poses["estimate_cpu_s"] / poses["frames"])
            ms, after, process, _ = _cost_run(images, calib, folder / f"given{i}",
                                              folder / "estimated0/ego_poses_estimated.csv")
            rows["given"].append((ms, after, process))
            print(f"cost run {i + 1}: estimated {times[0]:.0f} ms a frame ({times[1]:.0f} after the first "
                  f"{COST_WARMUP_FRAMES}), given {ms:.0f} ms ({after:.0f}): {100 * (times[1] / after - 1):+.1f} % "
                  f"after the first {COST_WARMUP_FRAMES}; the process's CPU {times[2]:.0f} against {process:.0f} ms "
                  f"a frame ({100 * (times[2] / process - 1):+.1f} %); estimation {cpu[-1]:.1f} ms of the reader "
                  f"thread's CPU a frame; load {os.getloadavg()[0]:.1f}")
        est, giv = (statistics.median(r[0] for r in rows[k]) for k in ("estimated", "given"))
        est_after, giv_after = (statistics.median(r[1] for r in rows[k]) for k in ("estimated", "given"))
        est_cpu, giv_cpu = (statistics.median(r[2] for r in rows[k]) for k in ("estimated", "given"))
        print(f"cost: {COST_FRAMES} frames of KITTI raw 0002 (1242x375), {runs} runs each, medians: estimated "
              f"{est:.0f} against given {giv:.0f} ms a frame ({100 * (est / giv - 1):+.1f} %), after the first "
              f"{COST_WARMUP_FRAMES} frames {est_after:.0f} against {giv_after:.0f} ms "
              f"({100 * (est_after / giv_after - 1):+.1f} %; the pairs' median "
              f"{100 * statistics.median(e[1] / g[1] - 1 for e, g in zip(rows['estimated'], rows['given'])):+.1f} %); "
              f"estimation {statistics.median(cpu):.1f} ms of the reader thread's CPU a frame (median; "
              f"{min(cpu):.1f}-{max(cpu):.1f}), {100 * statistics.median(cpu) / giv_after:.0f} % of a frame's time "
              f"with the poses given; the process's CPU {est_cpu:.0f} against {giv_cpu:.0f} ms a frame "
              f"({100 * (est_cpu / giv_cpu - 1):+.1f} %)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kitti", type=Path, default=Path("../shared/samples/real/kitti"))
    parser.add_argument("--real", type=Path, default=Path("../shared/samples/real"),
                        help="the real samples (KITTI raw and MOT17 for the --static check)")
    parser.add_argument("--video", type=Path, default=None, help="a static camera's video (vtest.avi)")
    parser.add_argument("--only", choices=("kitti", "static", "cost", "parts"), default=None,
                        help="one part: the KITTI sequences, the static camera and --static checks, the cost in "
                             "pedenv run's frame loop (run only when asked: a few minutes) or where it goes")
    parser.add_argument("--runs", type=int, default=4, help="--only cost: runs of each kind")
    args = parser.parse_args()
    if args.only == "cost":
        cost(args.kitti, args.runs)
        return
    if args.only == "parts":
        parts(args.kitti)
        return
    if args.only != "static":
        kitti(args.kitti)
    if args.only != "kitti":
        if args.video is not None:
            static_video(args.video)
        static_checks(args.real, args.video)


def kitti(root: Path) -> None:
    """The three real KITTI sequences against their GPS/IMU."""
    kitti_raw(root)
    sequences = root / "tracking_sequences"
    oxts = sequences / "training/oxts/0001.txt"
    kitti_tracking(sequences, [0, 1], "kitti tracking_sequences 0001 frames 0-1", oxts)
    kitti_tracking(root / "tracking_mini", [10, 15, 20], "kitti tracking_mini 0001 frames 10, 15, 20", oxts)


if __name__ == "__main__":
    main()
