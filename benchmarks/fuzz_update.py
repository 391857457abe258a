"""Property fuzz of ``PedestrianEnvironmentModel.update()`` : counts, not a test.

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

from pedenv.config import Config
from pedenv.evaluation.fuzz import Outcome, run_sequence
from pedenv.localization import configure


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
