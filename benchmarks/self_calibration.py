"""Self-calibration: the camera estimated from the people it sees, against the truth or a reference.

    PYTHONPATH=src python benchmarks/self_calibration.py [--samples ../shared/samples/real]
        [--only synthetic|seeds|refinement|mot17|vtest|vehicle|sequences|cost] [--seeds 60]
        [--video vtest.avi] [--frames 800]

- synthetic: the built-in ``static-plaza`` scene (seed 0, 150 frames, a camera 6 m up, 20 deg
  down, 64.5 deg field of view), skeletons from the detector model (``yolo11n-pose-far``
  profile) and exact skeletons: the estimate against the truth, then the positions of the fused
  method with the true and with the estimated camera side by side, and with the estimate's
  uncertainty added to the covariances as ``pedenv run`` writes them.
- seeds: the same scene over ``--seeds`` seeds (0..n-1, 60 by default, about 4 min of a core;
  detector model): per seed the estimate's errors in its stated 1-sigma and the positions with the
  estimate (its uncertainty added) against those with the true camera; pooled over the seeds, the
  normalised errors' RMS (honest: about 1), the mean errors (the fit's bias) and the coverage (one
  calibration error is shared by a scene's positions, so only many scenes show whether the
  covariances are calibrated), also without the crowd's mean-height term, which a synthetic crowd
  drawn around the prior's mean lacks.
- refinement: the estimate as ``pedenv run`` refines it on a 60 s synthetic scene (first 200
  frames, then more), against the truth, and the true ground points cut with it again.
- mot17: the real network (``onnx``, ``far``) on MOT17-02, -04 and -09 (static cameras; 5 or
  6 images each), the estimate against UCMCTrack's camera (``ucmctrack_cam_para/``, itself an
  estimate), with the focal length free and with it taken from UCMCTrack; where the estimate
  stands, the fused method's positions with either camera against the box bottoms cut with
  UCMCTrack's ground.
- vtest: the real network on the first ``--frames`` frames of a street video (Debian's
  ``opencv-doc`` ``examples/data/vtest.avi``, all 795 by default, 30 min of a 2-core CPU): the
  estimate of each half, of the first 200, 400, 600 frames (the warm-up going on) and of all
  frames (stable over time?), and the people's heights the fit gives (1.5-1.9 m?).
- sequences: the eight KITTI tracking drives of ``kitti/tracking_sequences/`` (labels only),
  skeletons' ankle and eye points rendered from the pedestrians' 3D boxes with 2 px noise:
  height and tilt with the intrinsics known, against the plane of the boxes' bottoms.
- cost: what ``pedenv run`` adds per frame after the warm-up (the positions' spread of 30 people).
- vehicle: intrinsics known, height, tilt and roll from the people: KITTI tracking 0016 (3
  images; truth: a plane fitted to the bottoms of every labelled object's 3D box over the
  sequence's 209 frames) and nuScenes 0061 (5 cameras; truth: the calibrated mounting).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT.parent / "shared" / "samples" / "real"
DEFAULT_VIDEO = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
STATIC_MOT17 = ("MOT17-02-FRCNN", "MOT17-04-FRCNN", "MOT17-09-FRCNN")
#: ``fused`` settings of an exactly known camera and anatomical ankles (the synthetic scene).
EXACT = {"static_camera_tilt_std_deg": 0.0, "static_camera_height_std_m": 0.0, "ankle_keypoint_offset_m": 0.0,
         "ankle_keypoint_offset_std_m": 0.0}


def row(label: str, est, truth: tuple[float, float, float, float] | None) -> None:
    """One printed line: the estimate (and its 1-sigma) against the truth."""
    if isinstance(est, Exception):
        print(f"  {label:34s} refused: {est}")
        return
    s = est.uncertainty()
    text = (f"f {est.focal:7.1f}+-{s['focal_px']:5.1f}  H {est.height:5.2f}+-{s['height_m']:.2f}  "
            f"tilt {np.degrees(est.tilt):5.2f}+-{s['tilt_deg']:.2f}  roll {np.degrees(est.roll):5.2f}+-"
            f"{s['roll_deg']:.2f}  ({est.people} people, {est.observations} obs)")
    if truth is not None:
        f, h, t, r = truth
        text += (f"\n  {'':34s} truth f {f:7.1f}  H {h:5.2f}  tilt {np.degrees(t):5.2f}  roll {np.degrees(r):5.2f}"
                 f"  -> f {100 * (est.focal / f - 1):+.1f} %  H {100 * (est.height / h - 1):+.1f} %  tilt "
                 f"{np.degrees(est.tilt - t):+.2f} deg  roll {np.degrees(est.roll - r):+.2f} deg")
    print(f"  {label:34s} {text}")


def fit(obs, size, **kw):
    from pedenv.calibration.fit import estimate_camera
    from pedenv.errors import InputError

    try:
        return estimate_camera(obs, size, **kw)
    except InputError as exc:
        return exc


def observe_frames(images, backend):
    """Observations of images (RGB arrays) with ``backend``'s whole-image detection, boxes linked."""
    from pedenv.calibration.linking import linked_observations

    return linked_observations(backend.detect(image) for image in images)


def onnx_far():
    from pedenv.detection import backend_options, create_detector

    return create_detector("onnx", **backend_options("onnx", detection="far"))


def coverage(frames, camera, spec, fused: dict, estimate=None, details: bool = False) -> dict:
    """The fused method over ``frames`` seen by ``camera`` (skeletons from backend ``spec``): mean
    relative error and the share of errors within the 1- and 2-sigma ellipses, each estimate
    matched to the nearest truth whose box overlaps its box; ``estimate``: covariances widened by
    the calibration's (:func:`pedenv.calibration.spread.widen_state`)."""
    from pedenv.calibration.spread import widen_state
    from pedenv.config import Config
    from pedenv.detection import create_detector
    from pedenv.evaluation.matching import match_to_ground_truth
    from pedenv.model import PedestrianEnvironmentModel

    model = PedestrianEnvironmentModel(Config().replace(fused=fused))
    backend = create_detector(spec) if isinstance(spec, str) else spec()
    rel, d2 = [], []
    for frame in frames:
        frame = dataclasses.replace(frame, camera=camera)
        frame = dataclasses.replace(frame, detections=backend(frame))
        state = model.update(frame)
        if estimate is not None:
            state = widen_state(state, estimate)
        p, gt = state.pedestrians, frame.ground_truth
        match = match_to_ground_truth(p.boxes, p.positions[:, :2], gt.boxes, gt.positions[:, :2])
        for i in np.flatnonzero(match >= 0):
            err = p.positions[i, :2] - gt.positions[match[i], :2]
            rel.append(np.linalg.norm(err) / np.linalg.norm(gt.positions[match[i], :2]))
            d2.append(float(err @ np.linalg.solve(p.covariances[i], err)))
    d2a = np.array(d2)
    return {"rel_error_pct": 100 * float(np.mean(rel)), "within_1sigma": 100 * float(np.mean(d2a <= 1.0)),
            "within_2sigma": 100 * float(np.mean(d2a <= 4.0)), "count": len(d2), **({"d2": d2a} if details else {})}


def synthetic() -> None:
    from pedenv.calibration.geometry import parameters_of
    from pedenv.calibration.linking import BoxLinker
    from pedenv.calibration.observations import Observations, observations_of
    from pedenv.detection import create_detector
    from pedenv.records import Detections
    from pedenv.synthetic import generate_scenes

    scene = generate_scenes(0, ["static-plaza"])[0]
    truth_camera = scene.frames[0].camera
    truth = parameters_of(truth_camera)
    print("synthetic static-plaza (seed 0, 150 frames, exact truth)")
    for label, spec in (("detector model (yolo11n-pose-far)", "detector-model:yolo11n-pose-far"),
                        ("exact skeletons", "ground-truth")):
        backend, linker, parts = create_detector(spec), BoxLinker(), []
        for frame in scene.frames:
            det: Detections = backend(frame)
            parts.append(observations_of(det, frame.index, linker(det.boxes)))
        est = fit(Observations.concat(parts), (truth_camera.width, truth_camera.height), walking=True)
        row(label, est, truth)
        if isinstance(est, Exception):
            continue
        # as pedenv run: the fused method as with a given camera, the estimate's uncertainty added to the covariances
        for name, camera, fused, spread in (("true camera", truth_camera, EXACT, None),
                                            ("estimated camera", est.camera(), EXACT, None),
                                            ("estimated, spread", est.camera(), EXACT, est)):
            m = coverage(scene.frames, camera, spec, fused, spread)
            print(f"  {'':34s} positions, {name:20s}: rel error {m['rel_error_pct']:5.2f} %  within 1/2 sigma "
                  f"{m['within_1sigma']:.1f} / {m['within_2sigma']:.1f} %  ({m['count']} pairs)")


def seeds(count: int) -> None:
    """The static scene over ``count`` seeds (0..count-1; 150 frames each, detector model): each seed's
    calibration error in its stated 1-sigma, the fused method's positions with the estimate (its
    uncertainty added, as ``pedenv run`` writes them) against those with the true camera, and the
    coverage per seed and pooled (one calibration error is shared by a scene's positions: only many
    scenes together can show whether the covariances are calibrated)."""
    from pedenv.calibration.geometry import parameters_of
    from pedenv.calibration.linking import BoxLinker
    from pedenv.calibration.observations import Observations, observations_of
    from pedenv.detection import create_detector
    from pedenv.synthetic import generate_scenes

    spec = "detector-model:yolo11n-pose-far"
    print(f"static-plaza seeds 0-{count - 1} (150 frames each, {spec}): calibration error / its 1-sigma, positions "
          "with the estimate (its uncertainty added) / with the true camera, coverage within 1 / 2 sigma")
    z, ratios, pooled = [], [], {"true": [], "estimated": [], "estimated, no crowd offset": []}
    relative = []  # focal %, height %, tilt deg: the signed errors, whose mean is the fit's bias
    for seed in range(count):
        scene = generate_scenes(seed, ["static-plaza"])[0]
        camera = scene.frames[0].camera
        truth = np.array(parameters_of(camera))
        backend, linker, parts = create_detector(spec), BoxLinker(), []
        for frame in scene.frames:
            det = backend(frame)
            parts.append(observations_of(det, frame.index, linker(det.boxes)))
        est = fit(Observations.concat(parts), (camera.width, camera.height), walking=True)
        if isinstance(est, Exception):
            print(f"  seed {seed}: refused: {est}")
            continue
        error = np.array([est.focal, est.height, est.tilt, est.roll]) - truth
        z.append(error / est.std)
        true = coverage(scene.frames, camera, spec, EXACT, details=True)
        mine = coverage(scene.frames, est.camera(), spec, EXACT, est, details=True)
        pooled["true"].append(true["d2"])
        pooled["estimated"].append(mine["d2"])
        pooled["estimated, no crowd offset"].append(coverage(scene.frames, est.camera(), spec, EXACT,
                                                             without_crowd(est), details=True)["d2"])
        ratios.append(mine["rel_error_pct"] / true["rel_error_pct"])
        relative.append([100 * error[0] / truth[0], 100 * error[1] / truth[1], np.degrees(error[2])])
        print(f"  seed {seed:2d}: f {100 * error[0] / truth[0]:+5.1f} % ({z[-1][0]:+.1f} sigma)  H "
              f"{100 * error[1] / truth[1]:+5.1f} % ({z[-1][1]:+.1f})  tilt {np.degrees(error[2]):+.2f} deg "
              f"({z[-1][2]:+.1f})  positions {mine['rel_error_pct']:.2f} / {true['rel_error_pct']:.2f} % "
              f"({ratios[-1]:.2f}x)  within 1/2 sigma {mine['within_1sigma']:5.1f} / {mine['within_2sigma']:5.1f} % "
              f"(true camera {true['within_1sigma']:.1f} / {true['within_2sigma']:.1f} %)")
    if not z:
        return
    rms = np.sqrt(np.mean(np.square(z), axis=0))
    print(f"  pooled over {len(z)} seeds: RMS of the errors in sigmas f {rms[0]:.2f}  H {rms[1]:.2f}  "
          f"tilt {rms[2]:.2f}  roll {rms[3]:.2f} (honest: about 1); positions' ratio estimate / true median "
          f"{np.median(ratios):.2f}, "
          f"{np.sum(np.array(ratios) <= 1.5)} of {len(ratios)} within 1.5x")
    mean, sem = np.mean(relative, axis=0), np.std(relative, axis=0) / np.sqrt(len(relative))
    print(f"  mean error (the fit's bias, +- its standard error): f {mean[0]:+.2f} +- {sem[0]:.2f} %  H "
          f"{mean[1]:+.2f} +- {sem[1]:.2f} %  tilt {mean[2]:+.3f} +- {sem[2]:.3f} deg")
    for name, d2 in pooled.items():
        d2a = np.concatenate(d2)
        print(f"  pooled, {name:26s}: within 1/2 sigma {100 * np.mean(d2a <= 1):.1f} / "
              f"{100 * np.mean(d2a <= 4):.1f} % ({len(d2a)} pairs; ideal 39.3 / 86.5 %)")


def without_crowd(est):
    """``est`` without its crowd's mean-height term (:data:`pedenv.calibration.fit.CROWD_MEAN_STD_M`):
    the spread a synthetic crowd, drawn around the prior's mean, has."""
    from pedenv.calibration.fit import CROWD_MEAN_STD_M, PERSON_HEIGHT_MEAN_M

    cov = est.covariance.copy()
    cov[1, 1] -= (est.height * CROWD_MEAN_STD_M / PERSON_HEIGHT_MEAN_M) ** 2
    return dataclasses.replace(est, covariance=cov)


def refinement() -> None:
    """The estimate as ``pedenv run`` refines it: a 60 s ``static-plaza`` scene (seed 0), the detector
    model's skeletons, the camera fitted to the first 200 frames (the warm-up) and to every 150
    more; each against the truth, and the scene's true ground points seen by the true camera cut
    with it again (the calibration's own share of the positions' error)."""
    from pedenv.calibration.geometry import camera_rotation, ground_points, intrinsics, parameters_of, project
    from pedenv.calibration.linking import BoxLinker
    from pedenv.calibration.observations import Observations, observations_of
    from pedenv.detection import create_detector
    from pedenv.synthetic import generate_scenes

    scene = generate_scenes(0, ["static-plaza"], duration_s=60.0)[0]
    camera = scene.frames[0].camera
    truth, size = parameters_of(camera), (camera.width, camera.height)
    backend, linker, parts = create_detector("detector-model:yolo11n-pose-far"), BoxLinker(), []
    for frame in scene.frames:
        det = backend(frame)
        parts.append(observations_of(det, frame.index, linker(det.boxes)))
    obs = Observations.concat(parts)
    xy = np.concatenate([f.ground_truth.positions[:, :2] for f in scene.frames])
    pixels = project(np.c_[xy, np.zeros(len(xy))], camera.intrinsics, camera.cam_to_vehicle[:3, :3], truth[1])
    inside = np.isfinite(pixels).all(axis=1) & (pixels >= 0).all(axis=1) & (pixels < size).all(axis=1)
    print("refinement: static-plaza 60 s (seed 0), detector model, the camera after n frames")
    for n in (200, 350, 500, 600):
        est = fit(obs.subset(obs.frames < n), size, walking=True)
        row(f"first {n} frames", est, truth)
        if isinstance(est, Exception):
            continue
        cut = ground_points(pixels[inside], intrinsics(est.focal, est.centre), camera_rotation(est.tilt, est.roll),
                            est.height)[:, :2]
        err = np.linalg.norm(cut - xy[inside], axis=1) / np.linalg.norm(xy[inside], axis=1)
        print(f"  {'':34s} true ground points cut again: mean relative error {100 * np.nanmean(err):.2f} %")


def mot17(samples: Path) -> None:
    from pedenv.calibration.fit import NETWORK_BODY
    from pedenv.calibration.geometry import parameters_of
    from pedenv.datasets import mot17 as mot
    from pedenv.datasets.ucmctrack import read_camera_parameters, static_camera
    from pedenv.images import read_image_rgb

    backend = onnx_far()
    print("MOT17 static sequences, real network (onnx far), against UCMCTrack's estimated camera")
    for name in STATIC_MOT17:
        seq = mot.read_sequence(samples / "mot17" / name)
        ref = static_camera(read_camera_parameters(samples / "mot17" / "ucmctrack_cam_para" / f"{name}.txt"),
                            seq.info.width, seq.info.height)
        truth = parameters_of(ref)
        obs = observe_frames([read_image_rgb(seq.image_path(n)) for n in seq.frames], backend)
        size = (seq.info.width, seq.info.height)
        row(f"{name} ({len(seq.frames)} images)", fit(obs, size, body=NETWORK_BODY, walking=True), truth)
        given = fit(obs, size, body=NETWORK_BODY, focal=truth[0], walking=True)
        row("  focal from UCMCTrack", given, truth)
        if not isinstance(given, Exception):
            positions(samples / "mot17" / name, ref, given)


def positions(folder: Path, reference, est) -> None:
    """The fused method on a MOT17 sequence with UCMCTrack's camera and with the estimate, against
    the box bottoms cut with UCMCTrack's ground (:func:`pedenv.datasets.ucmctrack.mot17_static_scene`)."""
    from pedenv.datasets.ucmctrack import mot17_static_scene

    scene = mot17_static_scene(folder, folder.parent / "ucmctrack_cam_para" / f"{folder.name}.txt")
    for name, camera, fused, spread in (("UCMCTrack camera", reference, {}, None),
                                        ("estimated camera", est.camera(), {}, None),
                                        ("estimated, spread", est.camera(), {}, est)):
        m = coverage(scene.frames, camera, onnx_far, fused, spread)
        print(f"  {'':34s} positions, {name:20s}: rel error {m['rel_error_pct']:5.2f} %  within 1/2 sigma "
              f"{m['within_1sigma']:.1f} / {m['within_2sigma']:.1f} %  ({m['count']} pairs)")


def vtest(video: Path, frames: int) -> None:
    from pedenv.apps.calibrate import warmup_frames
    from pedenv.calibration.fit import NETWORK_BODY

    if not video.is_file():
        print(f"vtest: {video} not found (apt-get install opencv-doc)")
        return
    images = [image for _, image in warmup_frames(None, video, frames, seconds=1e6)]
    obs = observe_frames(images, onnx_far())
    size = (images[0].shape[1], images[0].shape[0])
    half = len(images) // 2
    print(f"vtest.avi ({len(images)} frames), real network (onnx far), no truth: consistency")
    growing = [(f"frames 0-{n - 1}", obs.frames < n) for n in range(200, len(images), 200)]
    for label, keep in ((f"frames 0-{half - 1}", obs.frames < half), (f"frames {half}-{len(images) - 1}",
                        obs.frames >= half), *growing, ("all frames", obs.frames >= 0)):
        est = fit(obs.subset(keep), size, body=NETWORK_BODY, walking=True)
        row(label, est, None)
        if not isinstance(est, Exception):
            heights = person_heights(est, obs.subset(keep))
            print(f"  {'':34s} people's heights (median per track): median {np.median(heights):.2f} m, "
                  f"{100 * np.mean((heights >= 1.5) & (heights <= 1.9)):.0f} % within 1.5-1.9 m")


def person_heights(est, obs) -> np.ndarray:
    """Each track's median height (m) under ``est``: the eye keypoint's height over the ankles'
    ground point, divided by the network body's eye share."""
    from pedenv.body import ANKLE
    from pedenv.calibration.fit import NETWORK_BODY
    from pedenv.calibration.geometry import camera_rotation, ground_points, intrinsics

    k, r = intrinsics(est.focal, est.centre), camera_rotation(est.tilt, est.roll)
    ground = ground_points(obs.feet, k, r, est.height, NETWORK_BODY.ankle_m())
    ray = np.c_[obs.heads, np.ones(len(obs))] @ np.linalg.inv(k).T @ r.T
    horizontal = np.hypot(ground[:, 0], ground[:, 1])
    ray_h = np.hypot(ray[:, 0], ray[:, 1])
    eye_z = est.height + ray[:, 2] * horizontal / ray_h
    span = (obs.head_share - ANKLE) * NETWORK_BODY.span_scale
    tall = (eye_z - NETWORK_BODY.ankle_m()) / span
    return np.array([np.median(tall[obs.tracks == t]) for t in np.unique(obs.tracks)])


def vehicle(samples: Path) -> None:
    from pedenv.calibration.fit import NETWORK_BODY
    from pedenv.calibration.geometry import parameters_of
    from pedenv.datasets import kitti_files, nuscenes_cameras
    from pedenv.images import read_image_rgb
    from pedenv.records import Camera

    backend = onnx_far()
    print("vehicle cameras, intrinsics known: height, tilt, roll from the people (real network, onnx far)")
    training = samples / "kitti" / "tracking_mini" / "training"
    seq = kitti_files.read_tracking_sequence(training, "0016")
    labels = seq.labels
    solid = np.isin(labels.types, ("Pedestrian", "Car", "Van", "Cyclist", "Truck"))
    loc = labels.locations[solid]  # bottom-face centres, rectified camera frame (x right, y down, z forward)
    a = np.c_[np.ones(len(loc)), loc[:, 2], loc[:, 0]]
    h, slope_z, slope_x = np.linalg.lstsq(a, loc[:, 1], rcond=None)[0]
    truth = (float(seq.calib.K[0, 0]), float(h), float(np.arctan(-slope_z)), float(np.arctan(slope_x)))
    images = [read_image_rgb(seq.image_path(n)) for n in seq.frames]
    obs = observe_frames(images, backend)
    k = seq.calib.K
    size = (images[0].shape[1], images[0].shape[0])
    row("KITTI tracking 0016 (3 images)", fit(obs, size, body=NETWORK_BODY, focal=float(k[0, 0]),
                                               centre=(float(k[0, 2]), float(k[1, 2]))), truth)
    for cam in nuscenes_cameras.read_cameras(samples / "nuscenes-0061"):
        level = np.linalg.inv(cam.ego_to_global) @ cam.cam_to_global
        mount = np.eye(4)
        mount[:3, :3] = level[:3, :3]
        mount[2, 3] = level[2, 3]
        image = read_image_rgb(cam.image_path)
        truth = parameters_of(Camera(cam.K, image.shape[1], image.shape[0], mount))
        obs = observe_frames([image], backend)
        row(f"nuScenes {cam.camera}", fit(obs, (image.shape[1], image.shape[0]), body=NETWORK_BODY,
                                          focal=float(cam.K[0, 0]), centre=(float(cam.K[0, 2]), float(cam.K[1, 2]))),
            truth)


def sequences(samples: Path) -> None:
    """KITTI tracking_sequences, skeletons rendered from the labels: each pedestrian's ankle and
    eye points (anatomical shares of the box height) projected with 2 px noise, the camera's
    height and tilt fitted with its intrinsics, against the plane of the labelled boxes' bottoms."""
    from pedenv.calibration.observations import rendered_observations
    from pedenv.datasets import kitti_files
    from pedenv.errors import InputError

    training = samples / "kitti" / "tracking_sequences" / "training"
    rng = np.random.default_rng(0)
    print("KITTI tracking_sequences, skeletons rendered from the labels (real geometry, modelled perception); "
          "truth: the plane of the labelled boxes' bottoms (KITTI's nominal camera height: 1.65 m)")
    for name in sorted(p.stem for p in (training / "label_02").glob("*.txt")):
        calib = kitti_files.read_calib(training / "calib" / f"{name}.txt")
        try:
            labels = kitti_files.read_labels(training / "label_02" / f"{name}.txt")
        except InputError as exc:
            print(f"  seq {name}: not read ({exc})")
            continue
        k = calib.K
        obs, _ = rendered_observations(labels.of_type("Pedestrian"), k, rng)
        h, tilt, _ = labels.camera_over_ground()
        size = (int(round(2 * k[0, 2])), int(round(2 * k[1, 2])))
        est = fit(obs, size, focal=float(k[0, 0]), centre=(float(k[0, 2]), float(k[1, 2])))
        row(f"seq {name} ({len(np.unique(obs.tracks))} people)", est, (float(k[0, 0]), h, tilt, 0.0))


def cost() -> None:
    """What the run adds per frame after the warm-up: the spread of 30 people's positions."""
    import timeit

    from pedenv.calibration.estimate import CameraEstimate
    from pedenv.calibration.spread import calibration_covariances

    est = CameraEstimate(1266.4, 6.0, np.radians(20.0), 0.0, np.diag([50.0, 0.17, 0.01, 0.004]) ** 2, (1600, 900),
                         (800.0, 450.0), 10, 100, 3.0)
    rng = np.random.default_rng(0)
    people = np.c_[rng.uniform(8, 60, 30), rng.uniform(-20, 20, 30), np.zeros(30)]
    n = 500
    seconds = timeit.timeit(lambda: calibration_covariances(people, est), number=n) / n
    print(f"cost after the warm-up: {1e3 * seconds:.2f} ms per frame of 30 people (the positions' spread)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--only", choices=("synthetic", "seeds", "refinement", "mot17", "vtest", "vehicle", "sequences",
                                           "cost"))
    parser.add_argument("--video", type=Path, default=DEFAULT_VIDEO)
    parser.add_argument("--seeds", type=int, default=60, help="seeds: how many static scenes (seeds 0..n-1)")
    parser.add_argument("--frames", type=int, default=800, help="vtest: its first frames (all 795 by default)")
    args = parser.parse_args(argv)
    if args.only in (None, "synthetic"):
        synthetic()
    if args.only in (None, "seeds"):
        seeds(args.seeds)
    if args.only in (None, "refinement"):
        refinement()
    if args.only in (None, "mot17"):
        mot17(args.samples)
    if args.only in (None, "vtest"):
        vtest(args.video, args.frames)
    if args.only in (None, "vehicle"):
        vehicle(args.samples)
    if args.only in (None, "sequences"):
        sequences(args.samples)
    if args.only in (None, "cost"):
        cost()
    return 0


if __name__ == "__main__":
    sys.exit(main())
