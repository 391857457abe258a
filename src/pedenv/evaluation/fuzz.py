"""Fuzzed sequences for ``PedestrianEnvironmentModel.update()``: whatever skeletons, ego motion and
time steps arrive, ``update()`` returns only finite numbers and raises nothing but
:class:`~pedenv.errors.InputError`.

Each sequence (its own seed) runs 2-4 frames through a fresh model; its 1-3 persons keep one kind
of skeleton over the frames (:data:`KINDS`: plausible, small, far, collapsed to one point, on one
line, with 1-3 seen keypoints, all NaN, all unconfident, near the image's edges). Cameras, ego
speeds, turns, jumps and frame intervals (:data:`INTERVALS`) are drawn too. :func:`run_sequence`
runs one and counts what went wrong in an :class:`Outcome`. ``benchmarks/fuzz_update.py`` runs
100,000 of them; ``tests/test_model_fuzz.py`` a seeded share.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from pedenv.body import STANDING
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame
from pedenv.state import EnvironmentState

#: The skeleton kinds a person of a fuzzed sequence can have.
KINDS = ("plausible", "small", "far", "collapsed", "line", "few", "nan", "unconfident", "edge")
#: Frame intervals, seconds.
INTERVALS = (1e-3, 0.033, 0.1, 0.1, 0.5, 2.0, 30.0)
#: The arrays of the reported pedestrians that must be finite.
FIELDS = ("positions", "velocities", "covariances", "keypoints", "confidences", "boxes", "keypoints_3d", "distances")
#: A 2D upright skeleton, shares of the body height: u to the right, v up from the feet.
TEMPLATE = np.column_stack([-STANDING[:, 1], STANDING[:, 2]])
DEFAULT_CAMERA = Camera.from_fov(1600, 900, 64.5)


def fuzz_camera(rng: np.random.Generator) -> Camera:
    """The usual 1600x900 camera, or now and then another size, field of view and mount."""
    if rng.random() < 0.7:
        return DEFAULT_CAMERA
    w = int(rng.choice([64, 640, 1600, 3840]))
    h = int(max(8, w * rng.choice([0.25, 0.5625, 0.75, 1.0])))
    return Camera.from_fov(w, h, float(rng.uniform(20.0, 120.0)), height_m=float(rng.uniform(0.2, 3.0)),
                           forward_m=float(rng.uniform(-1.0, 2.0)))


def fuzz_person(rng: np.random.Generator, cam: Camera) -> tuple[str, np.ndarray, np.ndarray]:
    """One person's kind, keypoints (17, 2) pixels and confidences (17,) in the first frame."""
    kind = str(rng.choice(KINDS))
    w, h = cam.width, cam.height
    horizon = cam.intrinsics[1, 2] + rng.normal(0.0, 0.05 * h)
    foot = np.array([rng.uniform(0, w - 1), rng.uniform(0, h - 1)])
    size = rng.uniform(0.03, 0.9) * h
    if kind == "small":
        foot[1], size = horizon + rng.uniform(-5.0, 40.0), rng.uniform(1.0, 20.0)
    elif kind == "far":
        foot[1], size = horizon + rng.uniform(-3.0, 3.0), 10.0 ** rng.uniform(-3.0, 0.5)
    kp = foot + size * TEMPLATE * [1.0, -1.0]
    conf = rng.uniform(0.3, 1.0, 17) if rng.random() < 0.5 else np.full(17, 0.9)
    if kind == "collapsed":
        kp = np.tile(foot, (17, 1)) + rng.choice([0.0, 1e-9, 1e-3, 0.3]) * rng.normal(size=(17, 2))
    elif kind == "line":
        axis = int(rng.integers(0, 2))
        kp[:, axis] = foot[axis]  # zero width or zero height
    elif kind == "few":
        seen = rng.choice(17, int(rng.integers(1, 4)), replace=False)
        conf = np.where(np.isin(np.arange(17), seen), conf, rng.choice([0.0, np.nan]))
    elif kind == "nan":
        kp = np.full((17, 2), np.nan)
    elif kind == "unconfident":
        conf = np.full(17, rng.choice([0.0, -1.0, -1e-9]))
    elif kind == "edge":
        kp = np.clip(kp + rng.choice([-1, 1], 2) * rng.uniform(0.0, 2.0 * w, 2), [-1.0, -1.0], [w, h])
    return kind, kp, conf


@dataclass
class Outcome:
    """What fuzzed sequences gave: frames run, bad frames, refusals and exceptions by type."""

    sequences: int = 0
    frames: int = 0
    nan_frames: int = 0
    bad_covariance_frames: int = 0
    phantom_frames: int = 0
    refused: int = 0
    exceptions: Counter = field(default_factory=Counter)
    first_seed: dict = field(default_factory=dict)  # what went wrong -> the first seed it happened in

    def note(self, what: str, seed: int) -> None:
        self.first_seed.setdefault(what, seed)

    def add(self, other: Outcome) -> None:
        self.sequences += other.sequences
        self.frames += other.frames
        self.nan_frames += other.nan_frames
        self.bad_covariance_frames += other.bad_covariance_frames
        self.phantom_frames += other.phantom_frames
        self.refused += other.refused
        self.exceptions.update(other.exceptions)
        for k, v in other.first_seed.items():
            self.first_seed.setdefault(k, v)


def psd(cov: np.ndarray) -> bool:
    """Whether every (N, 2, 2) covariance is symmetric positive semi-definite (to rounding)."""
    a, b, c, d = cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 0], cov[:, 1, 1]
    scale = np.maximum(np.abs(a) + np.abs(d), 1e-300)
    return bool(np.all(a >= 0) and np.all(d >= 0) and np.all(np.abs(b - c) <= 1e-9 * scale)
                and np.all(a * d - b * c >= -1e-9 * scale**2))


def finite_state(state: EnvironmentState, model: PedestrianEnvironmentModel) -> bool:
    p, f = state.pedestrians, model.tracks.filter
    return (all(np.isfinite(getattr(p, name)).all() for name in FIELDS) and np.isfinite(f.x).all()
            and np.isfinite(f.P).all() and np.isfinite(state.ego.translation).all())


def run_sequence(seed: int, method: str, configs: dict[str, Config], reraise: bool = False) -> Outcome:
    """One fuzzed sequence (``seed``) through a fresh model of ``method``; ``reraise``: let
    an exception other than InputError through (to see its traceback)."""
    rng = np.random.default_rng(seed)
    out = Outcome(sequences=1)
    cam = fuzz_camera(rng)
    people = [fuzz_person(rng, cam) for _ in range(int(rng.integers(1, 4)))]
    drift = rng.choice([0.0, 0.0, 0.5, 3.0, 20.0])  # pixels per frame
    grow = rng.choice([1.0, 1.0, 1.02, 0.9])  # scale per frame
    jitter = rng.choice([0.0, 0.0, 1e-6, 0.5, 2.0])
    speed, turn = rng.choice([0.0, 0.2, 2.0, 10.0, 30.0]), rng.choice([0.0, 0.0, 0.1, 1.0])
    x, y, yaw = rng.uniform(-1e3, 1e3, 2).tolist() + [float(rng.uniform(-np.pi, np.pi))]
    model = PedestrianEnvironmentModel(configs[method])
    t = float(rng.uniform(0.0, 1e4))
    for i in range(int(rng.integers(2, 5))):
        dt = float(rng.choice(INTERVALS)) if i else 0.0
        t, yaw = t + dt, yaw + turn * dt
        x, y = x + speed * dt * np.cos(yaw), y + speed * dt * np.sin(yaw)
        if rng.random() < 0.05:
            x += float(rng.normal(0.0, 50.0))  # a localisation jump
        kps, confs = [], []
        for _, kp, conf in people:
            centre = kp[16] if np.isfinite(kp[16]).all() else np.zeros(2)
            moved = centre + grow**i * (kp - centre) + i * drift * np.array([1.0, 0.2])
            kps.append(moved + jitter * rng.normal(size=kp.shape))
            confs.append(conf)
        out.frames += 1
        try:
            det = Detections(np.array(kps), np.array(confs))
            state = model.update(Frame(i, t, cam, EgoPose.from_xy_yaw(x, y, yaw), detections=det))
        except InputError:
            out.refused += 1
            continue
        except Exception as exc:  # noqa: BLE001 - what the fuzz counts
            if reraise:
                raise
            name = type(exc).__name__
            out.exceptions[name] += 1
            out.note(f"{method} {name}: {exc}"[:160], seed)
            return out
        if not finite_state(state, model):
            out.nan_frames += 1
            out.note(f"{method} NaN/inf", seed)
        elif not psd(state.pedestrians.covariances):
            out.bad_covariance_frames += 1
            out.note(f"{method} covariance not PSD", seed)
        if (state.pedestrians.confidences <= 0).all(axis=1).any():
            out.phantom_frames += 1
            out.note(f"{method} pedestrian without a seen keypoint", seed)
    return out
