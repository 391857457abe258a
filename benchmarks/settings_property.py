"""Settings that are accepted work: every saved setting drawn inside its declared range, the model
run on built-in scenes and the detection modes on real sample images.

Every field of every section of ``pedenv.config.SECTIONS`` is drawn (seeded, ``pedenv.settings_draw``):
seed 0 at every field's minimum, seed 1 at its maximum, the others each field at its minimum, its
maximum, a random value inside its range, its ``off`` value or its default. Fields whose drawn values
contradict one another are reset to their defaults one at a time until the config is accepted. Each
config runs a fresh model over three built-in scenes (a turning ego, a crowd, a static camera; 2 s at
10 Hz, the ``detector-model`` backend's detections); the first ``--detection-configs`` configs also run
each detection mode (``fast``, ``far``, ``stream``) of the ONNX pose network with their drawn
``detection`` and ``merge`` sections on one KITTI and one MOT17 sample image (the network is slow on
a CPU). A failure is any exception but ``InputError``, a NaN or infinity in the state or the
detections, or no end within ``pedenv.settings_draw.HANG_LIMIT_S``.

    PYTHONPATH=src python benchmarks/settings_property.py --configs 320 --detection-configs 6

prints the counts: configurations drawn, accepted, fields reset, frames run, failures (each listed).
"""

from __future__ import annotations

import argparse
import dataclasses
import signal
import time
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.errors import InputError
from pedenv.settings_draw import HANG_LIMIT_S, build, draw_config, run_model, scene_frames

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SAMPLES = ROOT.parent / "shared" / "samples" / "real"
#: The detection modes run on the real images.
DETECTION_MODES = ("fast", "far", "stream")


def sample_images(samples: Path) -> list[tuple[str, np.ndarray, Any]]:
    """(key, RGB image, camera geometry or None) of the first frame of the first KITTI tracking
    sequence (level camera, 1.65 m up) and of the first MOT17 sequence (no geometry)."""
    import cv2

    from pedenv.datasets import kitti_files as kitti
    from pedenv.datasets import mot17
    from pedenv.detection.geometry import CameraGeometry
    from pedenv.evaluation.detections import KITTI_CAMERA_HEIGHT_M

    out = []
    training = samples / "kitti" / "tracking_mini" / "training"
    name = kitti.tracking_sequence_names(training)[0]
    seq = kitti.read_tracking_sequence(training, name)
    path = seq.image_path(seq.frames[0])
    out.append((f"kitti/{name}", path, CameraGeometry.level(seq.calib.K, KITTI_CAMERA_HEIGHT_M)))
    folder = mot17.sequence_folders(samples / "mot17")[0]
    mseq = mot17.read_sequence(folder)
    out.append((f"mot17/{folder.name}", mseq.image_path(mseq.frames[0]), None))
    images = []
    for key, p, geometry in out:
        bgr = cv2.imread(str(p), cv2.IMREAD_COLOR)
        if bgr is None:
            raise SystemExit(f"{p}: not a readable image")
        images.append((key, np.ascontiguousarray(bgr[..., ::-1]), geometry))
    return images


def detector(mode: str, config: Any) -> Any:
    """The ONNX detector in ``mode`` with the config's ``detection`` and ``redetect`` sections
    (the one place this benchmark reaches the detection stage)."""
    from pedenv.detection import create_detector

    return create_detector("onnx", detection=dataclasses.replace(config.detection, mode=mode),
                           redetect=config.redetect)


def _hang(_signum: int, _frame: Any) -> None:
    raise TimeoutError(f"no end after {HANG_LIMIT_S} s")


def run_detection(config: Any, images: list) -> tuple[int, int, list[str]]:
    """Each mode on each image: (detections run, refused with InputError, failures)."""
    done = refused = 0
    failures = []
    for mode in DETECTION_MODES:
        for key, rgb, geometry in images:
            signal.signal(signal.SIGALRM, _hang)
            signal.alarm(HANG_LIMIT_S)
            try:
                det = detector(mode, config).detect(rgb, geometry)
                arrays = [np.asarray(det.boxes, float), np.asarray(det.scores, float)]
                if not all(np.isfinite(a).all() for a in arrays):
                    failures.append(f"{mode} {key}: boxes or scores not finite")
                done += 1
            except InputError:
                refused += 1
            except Exception as exc:  # the property: nothing but InputError
                failures.append(f"{mode} {key}: {type(exc).__name__}: {exc}")
            finally:
                signal.alarm(0)
    return done, refused, failures


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configs", type=int, default=320, help="configurations drawn (seeds 0..N-1)")
    parser.add_argument("--detection-configs", type=int, default=6,
                        help="of them, how many also run the detection modes on the real images")
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    args = parser.parse_args(argv)

    t0 = time.perf_counter()
    frames = scene_frames()
    images = sample_images(args.samples) if args.detection_configs > 0 else []
    counts: Counter = Counter()
    resets: Counter = Counter()
    failures: list[str] = []
    for seed in range(args.configs):
        data = draw_config(np.random.default_rng(seed), {0: "min", 1: "max"}.get(seed))
        config, reset, refused = build(data)
        counts["drawn"] += 1
        resets.update(reset)
        if config is None:
            counts["refused"] += 1
            print(f"seed {seed}: refused after resetting {len(reset)} fields: {refused}")
            continue
        counts["accepted"] += 1
        done, frames_refused, failure = run_model(config, frames)
        counts["frames"] += done
        counts["frames refused (InputError)"] += frames_refused
        if failure:
            failures.append(f"seed {seed} model: {failure}")
        if seed < args.detection_configs:
            d_done, d_refused, d_failures = run_detection(config, images)
            counts["detections"] += d_done
            counts["detections refused (InputError)"] += d_refused
            failures += [f"seed {seed} detection {f}" for f in d_failures]
    print(f"configurations drawn: {counts['drawn']}, accepted: {counts['accepted']}, refused: {counts['refused']}")
    print(f"model: {counts['frames']} frames run on {len(frames)} scenes, "
          f"{counts['frames refused (InputError)']} refused with an InputError")
    print(f"detection: {counts['detections']} runs ({len(DETECTION_MODES)} modes x {len(images)} real images "
          f"x {min(args.detection_configs, args.configs)} configs), "
          f"{counts['detections refused (InputError)']} refused with an InputError")
    print(f"fields reset to their defaults (contradicting draws): {sum(resets.values())}; most often: "
          + ", ".join(f"{k} {v}" for k, v in resets.most_common(5)))
    print(f"failures: {len(failures)}")
    for line in failures:
        print(f"  {line}")
    print(f"{time.perf_counter() - t0:.0f} s")
    return 1 if failures else 0


if __name__ == "__main__":
    raise SystemExit(main())
