"""Property fuzz of ``PedestrianEnvironmentModel.update()`` (issue 19): counts, not a test.

    PYTHONPATH=src python benchmarks/fuzz_update.py --sequences 100000      # both methods
    PYTHONPATH=src python benchmarks/fuzz_update.py --sequences 100000 --workers 3
    PYTHONPATH=src python benchmarks/fuzz_update.py --sequences 2000 --method fused --seed 7

The property: whatever skeletons, ego motion and time steps arrive, ``update()`` returns
only finite numbers (every array of the state, and the Kalman filter's own state) and
raises nothing but :class:`~pedenv.errors.InputError`. Each sequence (its own seed) runs
2-4 frames through a fresh model; its 1-3 persons keep one kind of skeleton over the frames
(drifting and rescaling a little, or repeated exactly): plausible, small (1-20 px) and far
(below 3 px) near the horizon, collapsed to one point, on one line, with 1-3 seen
keypoints, all NaN, all unconfident, near the image's edges. Cameras, ego speeds, turns,
jumps and frame intervals (1 ms to 30 s) are drawn too. Sequences alternate between the
methods. Prints the sequences and frames run, the frames with NaN or inf, with a reported
covariance that is not positive semi-definite, with a pedestrian made of a person with no
seen keypoint (all NaN or all confidences <= 0: ``unseen``), the InputError refusals, the other
exceptions by type (with the first seed of each, to reproduce with ``--seed``) and the
throughput. ``tests/test_model_fuzz.py`` runs a seeded share of these sequences.
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from pedenv.body import STANDING
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame

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


def finite_state(state, model: PedestrianEnvironmentModel) -> bool:
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


def fuzz(sequences: int, seed: int = 0, methods: tuple[str, ...] = ("paper", "fused"),
         report_every: float = 0.0) -> dict[str, Outcome]:
    """Run ``sequences`` fuzzed sequences (seeds ``seed``, ``seed + 1``, ...; methods in
    turn); returns the outcome per method. ``report_every`` > 0: print progress that often (s)."""
    configs = {m: configure(Config(), m) for m in methods}
    outcomes = {m: Outcome() for m in methods}
    start = last = time.perf_counter()
    try:
        for k in range(sequences):
            method = methods[k % len(methods)]
            outcomes[method].add(run_sequence(seed + k, method, configs))
            now = time.perf_counter()
            if report_every > 0 and now - last >= report_every:
                last = now
                _progress(outcomes, now - start)
    except KeyboardInterrupt:  # SIGINT: the counts so far
        print(f"  interrupted after {sum(o.sequences for o in outcomes.values())} sequences", flush=True)
    return outcomes


def _progress(outcomes: dict[str, Outcome], seconds: float) -> None:
    done = sum(o.sequences for o in outcomes.values())
    counts = "; ".join(f"{m} {o.nan_frames} NaN, {o.bad_covariance_frames} non-PSD, {o.phantom_frames} "
                       f"unseen, {sum(o.exceptions.values())} exceptions" for m, o in outcomes.items())
    print(f"  {done} sequences, {done / seconds:.0f} sequences/s: {counts}", flush=True)


#: Sequences per task of a worker process (``--workers``).
CHUNK = 500


def _chunk(args: tuple[int, int, tuple[str, ...]]) -> dict[str, Outcome]:
    first, count, methods = args
    if first % len(methods):
        raise ValueError("chunks must start at a multiple of the method count")
    return fuzz(count, first, methods)


def fuzz_parallel(sequences: int, seed: int, methods: tuple[str, ...], workers: int,
                  report_every: float) -> dict[str, Outcome]:
    """:func:`fuzz` in ``workers`` processes, :data:`CHUNK` sequences a task: the same
    sequences (seeds) and counts as one process. ``seed`` must be a multiple of the methods."""
    import multiprocessing

    tasks = [(seed + k, min(CHUNK, sequences - k), methods) for k in range(0, sequences, CHUNK)]
    outcomes = {m: Outcome() for m in methods}
    start = last = time.perf_counter()
    with multiprocessing.get_context("fork").Pool(workers) as pool:
        parts = pool.imap_unordered(_chunk, tasks)
        try:
            for _ in tasks:
                while True:  # polled: a blocking wait would not see Ctrl-C
                    try:
                        part = parts.next(timeout=1.0)
                        break
                    except multiprocessing.TimeoutError:
                        continue
                for m, o in part.items():
                    outcomes[m].add(o)
                now = time.perf_counter()
                if report_every > 0 and now - last >= report_every:
                    last = now
                    _progress(outcomes, now - start)
        except KeyboardInterrupt:  # SIGINT: the counts of the chunks finished so far
            pool.terminate()
            print(f"  interrupted after {sum(o.sequences for o in outcomes.values())} sequences", flush=True)
    return outcomes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sequences", type=int, default=100_000, help="sequences to run, methods in turn")
    parser.add_argument("--seed", type=int, default=0, help="seed of the first sequence")
    parser.add_argument("--method", choices=["both", "paper", "fused"], default="both")
    parser.add_argument("--report-every", type=float, default=60.0, help="seconds between progress lines")
    parser.add_argument("--workers", type=int, default=1, help="processes (the counts do not depend on it)")
    parser.add_argument("--show", action="store_true", help="run only the sequence --seed of the first method "
                        "and show its outcome or its exception's traceback")
    args = parser.parse_args()
    methods = ("paper", "fused") if args.method == "both" else (args.method,)
    if args.show:
        print(run_sequence(args.seed, methods[0], {methods[0]: configure(Config(), methods[0])}, reraise=True))
        return
    start = time.perf_counter()
    if args.workers > 1:
        outcomes = fuzz_parallel(args.sequences, args.seed, methods, args.workers, args.report_every)
    else:
        outcomes = fuzz(args.sequences, args.seed, methods, args.report_every)
    wall = time.perf_counter() - start
    total = Outcome()
    print(f"{'method':8} {'sequences':>10} {'frames':>8} {'NaN/inf':>8} {'non-PSD':>8} {'unseen':>8} {'refused':>8}"
          f"  exceptions")
    for method, o in outcomes.items():
        total.add(o)
        exc = ", ".join(f"{k} {v}" for k, v in sorted(o.exceptions.items())) or "none"
        print(f"{method:8} {o.sequences:>10} {o.frames:>8} {o.nan_frames:>8} {o.bad_covariance_frames:>8} "
              f"{o.phantom_frames:>8} {o.refused:>8}  {exc}")
    for what, seed in sorted(total.first_seed.items()):
        print(f"  first seed {seed}: {what}")
    print(f"{total.sequences} sequences, {total.frames} frames in {wall:.1f} s: "
          f"{total.sequences / wall:.0f} sequences/s, {total.frames / wall:.0f} frames/s")


if __name__ == "__main__":
    main()
