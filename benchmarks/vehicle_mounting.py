"""A vehicle camera's mounting (height, pitch, roll) from its intrinsics, the people and the road.

    PYTHONPATH=src python benchmarks/vehicle_mounting.py [--samples ../shared/samples/real]
        [--only road|real|synthetic|drives] [--drives 0015,0004] [--no-positions]

- road: the road cues alone on real images (``pedenv.calibration.road``: the travel direction of the
  monocular visual odometry, and its road-plane scale against the step lengths of GPS/IMU or ORB-SLAM3):
  KITTI raw 2011_09_26_drive_0002 (10 frames, 9 m/s) against the travel direction GPS/IMU gives (the
  OXTS velocity, roll and pitch, the calibrated camera -> IMU chain) and against the IMU's forward axis;
  ``tracking_sequences`` 0001 frames 0-1 and ``tracking_mini`` 0001 frames 10, 15, 20 against
  ORB-SLAM3's stereo poses and the plane of the labelled boxes' bottoms.
- real: the real network (``onnx``, ``far``) on the real samples with their true mounting: KITTI
  ``tracking_mini`` 0016 (parked, 3 images; with the positions of the fused method, true and estimated
  mounting) and 0001 (driving, 3 images), ``object_samples`` (3
  single images), nuScenes 0061 (one image per camera): people, road and both combined.
- synthetic: the built-in vehicle scenes (exact truth: a camera 1.5 m up, level), people from the
  detector model, the road from the scenes' ego poses with :data:`STEP_NOISE_DEG` per step (its scale
  with :data:`STEP_SCALE_NOISE`); the
  positions of the fused method with the true and the estimated mounting.
- drives: the whole KITTI drives of ``tracking_sequences`` (labels only): skeletons' ankle and eye
  points rendered from the pedestrians' 3D boxes with 2 px noise (modelled perception), the road cue
  from ORB-SLAM3's stereo poses (the camera's real motion) with the monocular essential matrix's
  per-step noise added (:data:`STEP_NOISE_DEG`, measured by ``--only road``), and the road's scale
  (the camera's height from the ego poses' step lengths, ``pedenv.calibration.road.road_scale``) modelled
  as the nominal camera's odometry over the labelled ground with :data:`STEP_SCALE_NOISE` per step
  (measured by ``--only road``): people only, road only, people and road, people, road and scale,
  against the plane of the labelled boxes' bottoms; then the fused method's positions
  (detector model ``yolo11n-pose-far-kitti``, the dataset's ego poses) with the true mounting
  (KITTI's camera 1.65 m up, level) and with the estimate, side by side, and with the estimate given
  the data set's lever arm (its camera's place in the vehicle frame its ego poses move, which the
  estimate puts on the road under the camera).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT.parent / "shared" / "samples" / "real"
#: Per-step noise added to ORB-SLAM3's travel direction on the drives (elevation and yaw, degrees,
#: 1-sigma): the monocular essential matrix's RMS against GPS/IMU on the raw drive (``--only road``: 0.36, rounded up).
STEP_NOISE_DEG = 0.4
#: Per-step noise of the odometry's road-plane step length on the drives (log, 1-sigma): the nominal
#: camera's step lengths against GPS/IMU on the raw drive (``--only road``: 3.2 %, rounded up).
STEP_SCALE_NOISE = 0.035
#: The road scale's misses on real images (``--only road``: raw 0002 against KITTI's 1.65 m, tracking_mini
#: 0001 against its labelled ground): the drives' estimates are also given with the scale off by these.
SCALE_MISSES = (-0.026, 0.036)
#: A drive's frame-to-frame motion below this (metres) is no step (a parked car: the odometry's
#: parallax gate keeps no keyframe).
MIN_STEP_M = 0.2
def deg(x: float) -> str:
    return f"{np.degrees(x):+.2f}"


def show(label: str, est, truth: tuple[float, float] | None) -> None:
    """One line: the estimate (or its refusal) against the truth (height m, tilt rad)."""
    if isinstance(est, Exception):
        print(f"  {label:24s} refused: {est}")
        return
    s = est.uncertainty()
    text = (f"H {est.height:5.2f} +- {s['height_m']:.2f} m  tilt {np.degrees(est.tilt):5.2f} +- {s['tilt_deg']:.2f}  "
            f"roll {np.degrees(est.roll):5.2f} +- {s['roll_deg']:.2f} deg ({est.people} people)")
    if truth is not None:
        h, t = truth
        text += (f"  vs H {h:.2f} tilt {np.degrees(t):.2f}: H {100 * (est.height / h - 1):+.1f} % "
                 f"({(est.height - h) / max(s['height_m'], 1e-9):+.1f} sigma), tilt {deg(est.tilt - t)} deg "
                 f"({np.degrees(est.tilt - t) / max(s['tilt_deg'], 1e-9):+.1f} sigma)")
    road = est.road or {}
    if "disagreement_sigma" in road:
        text += f"  [road {road['pitch_deg']:.2f} deg, cues {road['disagreement_sigma']:.1f} sigma apart]"
    if "height_disagreement_sigma" in road:
        text += (f"  [scale {road['scale']['height_m']:.3f} m, {road['height_disagreement_sigma']:.1f} sigma from "
                 "the people]")
    elif "scale" in road:
        text += "  [no people: the road's pitch and scale]"
    print(f"  {label:24s} {text}")


def mounting(obs, size, k, body, road, scale=None):
    from pedenv.calibration.vehicle import estimate_mounting
    from pedenv.errors import InputError

    try:
        return estimate_mounting(obs, size, focal=float(k[0, 0]), centre=(float(k[0, 2]), float(k[1, 2])),
                                 body=body, road=road, scale=scale)
    except InputError as exc:
        return exc


def _kv(path: Path) -> dict[str, np.ndarray]:
    out = {}
    for line in path.read_text().splitlines():
        key, _, value = line.partition(":")
        try:
            out[key] = np.array([float(v) for v in value.split()])
        except ValueError:
            continue
    return out


def _rx(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _grey(path: Path) -> np.ndarray:
    import cv2

    from pedenv.images import read_image_rgb

    return cv2.cvtColor(read_image_rgb(path), cv2.COLOR_RGB2GRAY)


def _steps(images: list[np.ndarray], k: np.ndarray) -> list[np.ndarray]:
    """Each consecutive pair's travel direction (camera axes), the odometry's ``estimate_step``."""
    from pedenv.calibration.road import NOMINAL_MOUNTING, travel_direction
    from pedenv.odometry.motion import estimate_step

    out = []
    for a, b in zip(images[:-1], images[1:]):
        step = estimate_step(a, b, k, NOMINAL_MOUNTING)
        out.append(travel_direction(step.rotation, step.direction) if step.moved else np.full(3, np.nan))
    return out


def orbslam_directions(poses: np.ndarray, frames: list[int] | None = None) -> np.ndarray:
    """(S, 3) travel directions, camera axes, between consecutive ``frames`` of cam0 -> world ``poses``."""
    idx = list(range(len(poses))) if frames is None else frames
    moves = []
    for a, b in zip(idx[:-1], idx[1:]):
        d = poses[a, :3, :3].T @ (poses[b, :3, 3] - poses[a, :3, 3])
        moves.append(d / np.linalg.norm(d) if np.linalg.norm(d) >= MIN_STEP_M * (b - a) else np.full(3, np.nan))
    return np.array(moves).reshape(-1, 3)


def road_real(samples: Path) -> None:
    from pedenv.calibration.road import elevations, road_cue
    from pedenv.datasets import kitti_files
    from pedenv.odometry.reference import read_oxts

    raw = samples / "kitti" / "raw_2011_09_26_drive_0002"
    cc, vc, iv = (_kv(raw / f"calib_{n}.txt") for n in ("cam_to_cam", "velo_to_cam", "imu_to_velo"))
    k = cc["P_rect_02"].reshape(3, 4)[:, :3]
    imu_to_cam = cc["R_rect_00"].reshape(3, 3) @ vc["R"].reshape(3, 3) @ iv["R"].reshape(3, 3)
    oxts = read_oxts(sorted((raw / "2011_09_26_drive_0002_sync" / "oxts" / "data").glob("*.txt")))
    truth = np.array([imu_to_cam @ (_ry(o[4]) @ _rx(o[3])).T @ o[8:11] for o in oxts])  # velocity, camera axes
    truth = 0.5 * (truth[1:] + truth[:-1])
    images = [_grey(p) for p in sorted((raw / "2011_09_26_drive_0002_sync" / "image_02" / "data").glob("*.png"))]
    found = np.array(_steps(images, k))
    e, t = np.degrees(elevations(found)), np.degrees(elevations(truth))
    cue = road_cue(found)
    assert cue is not None
    imu_axis = float(np.degrees(elevations(imu_to_cam @ np.array([1.0, 0.0, 0.0]))[0]))
    print("road cue, real images (monocular visual odometry's travel direction; pitch > 0: the camera looks down)")
    print(f"  raw 2011_09_26_drive_0002, {len(found)} steps: per step images - GPS/IMU travel "
          f"{np.array2string(e - t, precision=2, separator=' ')} deg (RMS {np.sqrt(np.mean((e - t) ** 2)):.2f})")
    print(f"    pooled pitch {np.degrees(cue.pitch):+.2f} +- {np.degrees(cue.std):.2f} deg; GPS/IMU travel "
          f"{np.mean(t):+.2f} (error {np.degrees(cue.pitch) - np.mean(t):+.2f}); the IMU's forward axis "
          f"{imu_axis:+.2f} (error {np.degrees(cue.pitch) - imu_axis:+.2f})")
    road_height(raw, k, images, oxts)
    for folder, name, frames in ((samples / "kitti" / "tracking_sequences" / "training", "0001", [0, 1]),
                                 (samples / "kitti" / "tracking_mini" / "training", "0001", [10, 15, 20])):
        seq_k = kitti_files.read_calib(folder / "calib" / f"{name}.txt").K
        poses = kitti_files.read_camera_trajectory(folder / "ego_poses_orbslam3" / name / "CameraTrajectory.txt")
        imgs = [_grey(folder / "image_02" / name / f"{f:06d}.png") for f in frames]
        try:
            found = np.array(_steps(imgs, seq_k))
        except Exception as exc:  # noqa: BLE001 - the odometry's refusal is a result here
            print(f"  {folder.parent.name} {name} frames {frames}: odometry refused: {exc}")
            continue
        ref = orbslam_directions(poses, frames)
        _, tilt, _ = kitti_files.read_labels(folder / "label_02" / f"{name}.txt").camera_over_ground()
        cue = road_cue(found[np.isfinite(found).all(axis=1)])
        pitch = "no moving step" if cue is None else f"{np.degrees(cue.pitch):+.2f} +- {np.degrees(cue.std):.2f}"
        print(f"  {folder.parent.name} {name} frames {frames}: per step images "
              f"{np.array2string(np.degrees(elevations(found)), precision=2)} vs ORB-SLAM3 "
              f"{np.array2string(np.degrees(elevations(ref)), precision=2)} deg; pooled {pitch} deg; "
              f"labelled ground plane {np.degrees(tilt):+.2f}")
        tracking_scale(folder, name, frames, seq_k, poses)


def scale_steps(images: list[np.ndarray], k: np.ndarray, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The odometry (nominal camera, :data:`pedenv.calibration.road.NOMINAL_MOUNTING`) over ``images`` at
    ``times`` seconds: (S,) its moving steps' lengths, metres, and (S, 2) their first and last image."""
    from pedenv.calibration.road import NOMINAL_MOUNTING
    from pedenv.odometry.estimator import VisualOdometry

    odometry = VisualOdometry(k, NOMINAL_MOUNTING)
    for i, image in enumerate(images):
        odometry.update(image, float(times[i]), where=f"frame {i}")
    keys = np.searchsorted(times, odometry.key_timestamps)
    moved = np.array([s.moved for s in odometry.steps], bool)
    return odometry.lengths()[moved], np.c_[keys[:-1], keys[1:]][moved]


def road_height(raw: Path, k: np.ndarray, images: list[np.ndarray], oxts: np.ndarray) -> None:
    """The road's scale (:func:`pedenv.calibration.road.road_scale`) with GPS/IMU's step lengths: the
    camera's height over the road, against KITTI's 1.65 m."""
    from pedenv.calibration.road import road_scale
    from pedenv.odometry.reference import integrated_distance

    sync = raw / "2011_09_26_drive_0002_sync"
    stamps = np.array([np.datetime64(t.strip()) for t in (sync / "image_02/timestamps.txt").read_text().split("\n")
                       if t.strip()][: len(images)])
    times = (stamps - stamps[0]) / np.timedelta64(1, "s")
    lengths, spans = scale_steps(images, k, times)
    gps = np.array([integrated_distance(oxts[a:b + 1], times[a:b + 1]) for a, b in spans])
    scale = road_scale(lengths, gps)
    assert scale is not None
    print(f"    road scale with GPS/IMU's step lengths ({gps.sum():.2f} m): H {scale.height:.3f} +- {scale.std:.3f} m "
          f"from {scale.steps} steps (per step {np.array2string(1.5 * gps / lengths, precision=3)}); KITTI 1.65 m: "
          f"{100 * (scale.height / 1.65 - 1):+.1f} %")


def tracking_scale(folder: Path, name: str, frames: list[int], k: np.ndarray, poses: np.ndarray):
    """The road's scale on a tracking drive's real frames with ORB-SLAM3's (stereo, metric) step lengths."""
    from pedenv.calibration.road import road_scale
    from pedenv.datasets import kitti_files

    images = [_grey(folder / "image_02" / name / f"{f:06d}.png") for f in frames]
    lengths, spans = scale_steps(images, k, np.array(frames, float) / 10.0)
    ego = np.array([np.linalg.norm(poses[frames[b], :3, 3] - poses[frames[a], :3, 3]) for a, b in spans])
    scale = road_scale(lengths, ego)
    h, _, _ = kitti_files.read_labels(folder / "label_02" / f"{name}.txt").camera_over_ground()
    text = "no step" if scale is None else (f"H {scale.height:.3f} +- {scale.std:.3f} m from {scale.steps} steps "
                                            f"(labelled ground {h:.3f} m: {100 * (scale.height / h - 1):+.1f} %; "
                                            f"KITTI 1.65 m: {100 * (scale.height / 1.65 - 1):+.1f} %)")
    print(f"    road scale with ORB-SLAM3's step lengths ({ego.sum():.2f} m): {text}")
    return scale


def onnx_far():
    from pedenv.detection import backend_options, create_detector

    return create_detector("onnx", **backend_options("onnx", detection="far"))


def observe(images, backend):
    from pedenv.calibration.linking import linked_observations

    return linked_observations(backend.detect(image) for image in images)


def real(samples: Path) -> None:
    from pedenv.calibration.fit import NETWORK_BODY
    from pedenv.calibration.geometry import parameters_of
    from pedenv.calibration.road import road_cue
    from pedenv.datasets import kitti_files, nuscenes_cameras
    from pedenv.images import read_image_rgb
    from pedenv.records import Camera

    backend = onnx_far()
    print("real samples, real network (onnx far), intrinsics given; truth: the labelled boxes' ground plane "
          "(KITTI), the calibrated mounting (nuScenes)")
    training = samples / "kitti" / "tracking_mini" / "training"
    for name in ("0016", "0001"):
        seq = kitti_files.read_tracking_sequence(training, name)
        h, tilt, _ = seq.labels.camera_over_ground()
        rgb = [read_image_rgb(seq.image_path(n)) for n in seq.frames]
        obs = observe(rgb, backend)
        steps = np.array(_steps([_grey(seq.image_path(n)) for n in seq.frames], seq.calib.K))
        road = road_cue(steps[np.isfinite(steps).all(axis=1)])
        size = (rgb[0].shape[1], rgb[0].shape[0])
        print(f"  tracking_mini {name} frames {list(seq.frames)}: {len(obs)} person-images; "
              f"road: {'none (parked)' if road is None else f'{road.steps} steps'}")
        people = mounting(obs, size, seq.calib.K, NETWORK_BODY, None)
        show("people", people, (h, tilt))
        if not isinstance(people, Exception):
            from pedenv.datasets import open_dataset

            data = open_dataset("kitti", samples / "kitti" / "tracking_mini")
            compare_positions(lambda scene=name, kitti=data: kitti.frames(scene), onnx_far, people)
        if road is not None:
            show("people and road", mounting(obs, size, seq.calib.K, NETWORK_BODY, road), (h, tilt))
            poses = kitti_files.read_camera_trajectory(training / "ego_poses_orbslam3" / name / "CameraTrajectory.txt")
            scale = tracking_scale(training, name, list(seq.frames), seq.calib.K, poses)
            show("people, road, scale", mounting(obs, size, seq.calib.K, NETWORK_BODY, road, scale), (h, tilt))
    objects = samples / "kitti" / "object_samples" / "training"
    for path in sorted((objects / "image_2").glob("*.png")):
        calib = kitti_files.read_calib(objects / "calib" / f"{path.stem}.txt")
        image = read_image_rgb(path)
        show(f"object {path.stem}", mounting(observe([image], backend), (image.shape[1], image.shape[0]), calib.K,
                                             NETWORK_BODY, None), None)
    for cam in nuscenes_cameras.read_cameras(samples / "nuscenes-0061"):
        level = np.linalg.inv(cam.ego_to_global) @ cam.cam_to_global
        mount = np.eye(4)
        mount[:3, :3], mount[2, 3] = level[:3, :3], level[2, 3]
        image = read_image_rgb(cam.image_path)
        _, h, tilt, _ = parameters_of(Camera(cam.K, image.shape[1], image.shape[0], mount))
        show(f"nuScenes {cam.camera}", mounting(observe([image], backend), (image.shape[1], image.shape[0]), cam.K,
                                                NETWORK_BODY, None), (h, tilt))


def noisy(directions: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``directions`` (S, 3) turned by :data:`STEP_NOISE_DEG` of Gaussian noise in elevation and yaw."""
    d = directions[np.isfinite(directions).all(axis=1)]
    e = np.arctan2(-d[:, 1], np.hypot(d[:, 0], d[:, 2])) + rng.normal(0, np.radians(STEP_NOISE_DEG), len(d))
    y = np.arctan2(d[:, 0], d[:, 2]) + rng.normal(0, np.radians(STEP_NOISE_DEG), len(d))
    return np.c_[np.cos(e) * np.sin(y), -np.sin(e), np.cos(e) * np.cos(y)]


def modelled_lengths(positions: np.ndarray, height: float, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(odometry, ego) step lengths, metres, of the ego's ``positions`` (N, 3), one per frame: a step ends at
    the first frame at least :data:`~pedenv.calibration.road.MIN_SCALE_STEP_M` from its start (as the
    odometry's keyframes wait for motion); the ego's length from the poses, the odometry's as the nominal
    camera would measure it over a road ``height`` metres under the camera, with :data:`STEP_SCALE_NOISE`
    of log-normal noise per step."""
    from pedenv.calibration.road import MIN_SCALE_STEP_M, NOMINAL_MOUNTING

    steps, key = [], 0
    for i in range(1, len(positions)):
        length = float(np.linalg.norm(positions[i] - positions[key]))
        if length >= MIN_SCALE_STEP_M:
            steps.append(length)
            key = i
    ego = np.array(steps)
    odometry = ego * NOMINAL_MOUNTING[2, 3] / height * np.exp(rng.normal(0.0, STEP_SCALE_NOISE, len(ego)))
    return odometry, ego


def drives(samples: Path, names: list[str] | None, with_positions: bool) -> None:
    from pedenv.calibration.observations import rendered_observations
    from pedenv.calibration.road import road_cue, road_scale
    from pedenv.calibration.vehicle import estimate_mounting
    from pedenv.datasets import kitti_files
    from pedenv.errors import InputError

    training = samples / "kitti" / "tracking_sequences" / "training"
    print(f"KITTI tracking_sequences: people rendered from the labels (real geometry, modelled perception); road "
          f"from ORB-SLAM3's stereo poses + {STEP_NOISE_DEG} deg noise per step (real motion, modelled odometry); "
          "truth: the labelled boxes' ground plane")
    for name in names or sorted(p.stem for p in (training / "label_02").glob("*.txt")):
        rng = np.random.default_rng(0)
        calib = kitti_files.read_calib(training / "calib" / f"{name}.txt")
        labels = kitti_files.read_labels(training / "label_02" / f"{name}.txt")
        poses = kitti_files.read_camera_trajectory(training / "ego_poses_orbslam3" / name / "CameraTrajectory.txt")
        k = calib.K
        people = labels.of_type("Pedestrian")
        obs, seen = rendered_observations(people, k, rng)
        tall = float(np.mean(people.dimensions[seen, 0])) if seen.any() else float("nan")
        h, tilt, _ = labels.camera_over_ground()
        travel = orbslam_directions(poses)
        road = road_cue(noisy(travel, rng))
        size = (int(round(2 * k[0, 2])), int(round(2 * k[1, 2])))
        print(f"  seq {name}: {len(np.unique(obs.tracks))} people (mean labelled height {tall:.2f} m), "
              f"{0 if road is None else road.steps} steps of travel"
              + ("" if road is None else f" (road alone: pitch {np.degrees(road.pitch):.2f} +- "
                                         f"{np.degrees(road.std):.2f} deg, vs plane {deg(road.pitch - tilt)})"))
        scale = road_scale(*modelled_lengths(poses[:, :3, 3], h, rng))
        if scale is not None:
            print(f"    road scale alone (ORB-SLAM3's step lengths): H {scale.height:.3f} +- {scale.std:.3f} m from "
                  f"{scale.steps} steps ({100 * (scale.height / h - 1):+.1f} %)")
        kw = {"focal": float(k[0, 0]), "centre": (float(k[0, 2]), float(k[1, 2]))}
        ests = {}
        for label, cue, sc in (("people", None, None), ("people and road", road, None),
                               ("people, road, scale", road, scale)):
            if (label != "people" and road is None) or (label == "people, road, scale" and scale is None):
                continue
            try:
                ests[label] = estimate_mounting(obs, size, road=cue, scale=sc, **kw)
            except InputError as exc:
                ests[label] = exc
            show(label, ests[label], (h, tilt))
        best = ests.get("people, road, scale", ests.get("people"))
        if scale is not None and obs.people:
            shifted(obs, size, kw, road, scale, h)
        if with_positions and not isinstance(best, Exception) and best is not None:
            positions(samples, name, best)


def shifted(obs, size, kw: dict, road, scale, h: float) -> None:
    """The estimate of all cues with the road's scale off by :data:`SCALE_MISSES` and at KITTI's 1.65 m."""
    from pedenv.calibration.vehicle import estimate_mounting

    out = []
    for miss in (*SCALE_MISSES, 1.65 / scale.height - 1.0):
        off = dataclasses.replace(scale, height=scale.height * (1 + miss), std=scale.std * (1 + miss))
        est = estimate_mounting(obs, size, road=road, scale=off, **kw)
        out.append(f"{100 * miss:+.1f} % -> H {100 * (est.height / h - 1):+.1f} %")
    print(f"    the scale off (real images' misses; KITTI's 1.65 m): {', '.join(out)}")


def positions(samples: Path, name: str, est) -> None:
    """The fused method on drive ``name`` (its ego poses) with KITTI's mounting and with ``est``'s."""
    from pedenv.datasets import open_dataset

    data = open_dataset("kitti-tracking", samples / "kitti" / "tracking_sequences")
    compare_positions(lambda: data.frames(name), data.default_pose_backend, est)


def compare_positions(frames, spec, est) -> None:
    """The fused method over ``frames()`` (skeletons from backend ``spec``: a name, or a function that
    makes the backend) with their own camera and with ``est``'s mounting: mean relative error (to the
    ego) and the share within 1 and 2 sigma. ``est`` puts the ego poses' origin on the road under the
    camera; the last line gives it the data set's lever arm as a calibration's ``camera_position`` would (the
    camera's place in the vehicle frame the ego poses move: KITTI's colour camera sits 6 cm left of it),
    which people and road cannot show."""
    from pedenv.calibration.spread import widen_state
    from pedenv.config import Config
    from pedenv.detection import create_detector
    from pedenv.evaluation.matching import match_to_ground_truth
    from pedenv.model import PedestrianEnvironmentModel

    for label in ("true mounting", "estimated", "estimated, spread", "estimated, lever arm"):
        model = PedestrianEnvironmentModel(Config())
        backend = create_detector(spec) if isinstance(spec, str) else spec()
        rel, d2 = [], []
        for frame in frames():
            used = est
            if label == "estimated, lever arm":  # the calibration's camera_position
                used = dataclasses.replace(est, position=tuple(frame.camera.cam_to_vehicle[:2, 3]))
            if label != "true mounting":
                frame = dataclasses.replace(frame, camera=used.camera("vehicle"))
            frame = dataclasses.replace(frame, detections=backend(frame))
            state = model.update(frame)
            if label.startswith("estimated, "):
                state = widen_state(state, used, frame.ego)
            p, gt = state.pedestrians, frame.ground_truth
            match = match_to_ground_truth(p.boxes, p.positions[:, :2], gt.boxes, gt.positions[:, :2])
            for i in np.flatnonzero(match >= 0):
                local = gt.positions[match[i], :2] - frame.ego.translation[:2]
                err = p.positions[i, :2] - gt.positions[match[i], :2]
                rel.append(np.linalg.norm(err) / np.linalg.norm(local))
                d2.append(float(err @ np.linalg.solve(p.covariances[i], err)))
        d2a = np.array(d2)
        print(f"    positions, {label:20s}: rel error {100 * np.mean(rel):5.2f} %  within 1/2 sigma "
              f"{100 * np.mean(d2a <= 1):.1f} / {100 * np.mean(d2a <= 4):.1f} %  ({len(d2)} pairs)")


def synthetic() -> None:
    """The built-in vehicle scenes (exact truth: a camera 1.5 m up, level): people from the detector
    model, linked by box overlap; the road from the scene's ego poses with :data:`STEP_NOISE_DEG`."""
    from pedenv.calibration.geometry import parameters_of
    from pedenv.calibration.linking import BoxLinker
    from pedenv.calibration.observations import Observations, observations_of
    from pedenv.calibration.road import road_cue, road_scale
    from pedenv.detection import create_detector
    from pedenv.synthetic import generate_scenes

    spec = "detector-model:yolo11n-pose-far"
    print(f"synthetic vehicle scenes (seed 0; exact truth), people from the detector model ({spec}), road from the "
          f"ego poses + {STEP_NOISE_DEG} deg noise per step")
    for scene in generate_scenes(0):
        camera = scene.frames[0].camera
        if camera.static:
            continue
        _, h, tilt, _ = parameters_of(camera)
        backend, linker, parts, moves = create_detector(spec), BoxLinker(), [], []
        to_camera = camera.cam_to_vehicle[:3, :3].T
        for a, b in zip(scene.frames[:-1], scene.frames[1:]):
            step = a.ego.rotation.T @ (b.ego.translation - a.ego.translation)  # vehicle axes of frame a
            moves.append(to_camera @ step / np.linalg.norm(step) if np.linalg.norm(step) >= MIN_STEP_M
                         else np.full(3, np.nan))
        for frame in scene.frames:
            det = backend(frame)
            parts.append(observations_of(det, frame.index, linker(det.boxes)))
        obs = Observations.concat(parts)
        moving, rng = np.array(moves), np.random.default_rng(0)
        road = road_cue(noisy(moving, rng)) if np.isfinite(moving).all(axis=1).any() else None
        scale = road_scale(*modelled_lengths(np.array([f.ego.translation for f in scene.frames]), h, rng))
        print(f"  {scene.name}: {obs.people} people, {0 if road is None else road.steps} steps of travel")
        best = None
        for label, cue, sc in (("people", None, None), ("people and road", road, None),
                               ("people, road, scale", road, scale)):
            if (label != "people" and road is None) or (label == "people, road, scale" and scale is None):
                continue
            best = mounting(obs, (camera.width, camera.height), camera.intrinsics, None, cue, sc)
            show(label, best, (h, tilt))
        if best is not None and not isinstance(best, Exception):
            compare_positions(lambda frames=scene.frames: frames, spec, best)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--only", choices=("road", "real", "drives", "synthetic"))
    parser.add_argument("--drives", help="comma-separated drives (default: all of tracking_sequences)")
    parser.add_argument("--no-positions", action="store_true", help="drives: the mounting only")
    args = parser.parse_args(argv)
    if args.only in (None, "road"):
        road_real(args.samples)
    if args.only in (None, "real"):
        real(args.samples)
    if args.only in (None, "synthetic"):
        synthetic()
    if args.only in (None, "drives"):
        drives(args.samples, args.drives.split(",") if args.drives else None, not args.no_positions)
    return 0


if __name__ == "__main__":
    sys.exit(main())
