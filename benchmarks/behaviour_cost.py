"""The behaviour cues' cost inside ``model.update``, per frame, for several ``orientation_interval_s``
in one run: the synthetic scenes (seed 0, default detector model, ``fused`` preset, the predicted
path sampled as ``benchmarks/behaviour.py`` does) run through a fresh model per setting, the
settings taking turns scene by scene and round by round so that the shared machine's load falls
on all alike. For each setting the best round per scene is kept (the least disturbed), summed:
the wall time of ``model.update`` and, inside it, the behaviour estimator's own clock, and their
ratio (the cues' share of the rest of ``update``); of the cues, the clocks of the orientation
(``BehaviourEstimator._orient``, where the tree has it) and of the ego's path and the conflict
(``predict_ego_path``, ``conflict_of``). Detections are drawn before timing. With ``--cpu`` every
clock (``model.update``'s, the estimator's own, the parts') counts this process's CPU time
(``time.process_time``) instead of the wall time, so that other jobs on a shared machine count less.

    PYTHONPATH=src python benchmarks/behaviour_cost.py --intervals 0,0.3
    PYTHONPATH=src python benchmarks/behaviour_cost.py --intervals 0.3 --cpu --rounds 3
    PYTHONPATH=/tmp/beh-before/src python benchmarks/behaviour_cost.py --intervals 0   # a tree without the field
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from types import SimpleNamespace

from behaviour_synthetic import BENCH_HORIZONS

import pedenv.behaviour.estimator as estimator
from pedenv.behaviour.config import BehaviourConfig
from pedenv.config import Config
from pedenv.model import PedestrianEnvironmentModel
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.detector import DetectorModel


def config_of(interval_s: float) -> Config:
    """The benchmark's configuration with ``orientation_interval_s`` (a tree from before the field
    runs with 0: every frame)."""
    known = "orientation_interval_s" in BehaviourConfig.__dataclass_fields__
    if interval_s and not known:
        raise SystemExit("this tree has no behaviour.orientation_interval_s: use --intervals 0")
    extra = {"orientation_interval_s": interval_s} if known else {}
    return Config().replace(behaviour={"horizons_s": list(BENCH_HORIZONS), **extra})


#: Seconds spent in the parts of the cues timed apart (see :func:`install_clocks`).
CLOCKS = {"orientation": 0.0, "conflict": 0.0}
#: The clock of every figure (``time.process_time`` with ``--cpu``).
CLOCK = {"now": time.perf_counter}


def install_clocks(cpu: bool = False) -> None:
    """Time the estimator's orientation step and its calls of the ego path and the conflict; with
    ``cpu`` the estimator's own clock (``estimator.time.perf_counter``) becomes this process's CPU time."""
    if cpu:
        CLOCK["now"] = time.process_time
        estimator.time = SimpleNamespace(perf_counter=time.process_time)  # type: ignore[assignment]

    def timed(fn, key):
        def run(*args, **kwargs):
            start = CLOCK["now"]()
            try:
                return fn(*args, **kwargs)
            finally:
                CLOCKS[key] += CLOCK["now"]() - start
        return run

    estimator.conflict_of = timed(estimator.conflict_of, "conflict")
    estimator.predict_ego_path = timed(estimator.predict_ego_path, "conflict")
    if hasattr(estimator.BehaviourEstimator, "_orient"):
        estimator.BehaviourEstimator._orient = timed(estimator.BehaviourEstimator._orient, "orientation")
    else:
        CLOCKS["orientation"] = float("nan")


def time_scene(frames: list, config: Config) -> list[float]:
    """Wall time (s) of ``model.update`` over the frames, the behaviour cues' part of it, of that the
    orientation's and the ego path's and conflict's (s), and the number of pedestrians reported,
    with a fresh model."""
    model = PedestrianEnvironmentModel(config)
    wall, people, before = 0.0, 0, dict(CLOCKS)
    for frame in frames:
        start = CLOCK["now"]()
        state = model.update(frame)
        wall += CLOCK["now"]() - start
        people += len(state.pedestrians)
    assert model.behaviour is not None, "the fused preset computes the behaviour cues"
    return [wall, model.behaviour.elapsed_s, CLOCKS["orientation"] - before["orientation"],
            CLOCKS["conflict"] - before["conflict"], people]


def measure(names: list[str], intervals: list[float], rounds: int) -> dict[float, list[float]]:
    """Per interval the sums over the scenes (each scene's fastest round) of :func:`time_scene`'s
    figures, and the number of frames."""
    configs = {i: config_of(i) for i in intervals}
    totals = {i: [0.0] * 6 for i in intervals}
    for scene in generate_scenes(0, names):
        detector = DetectorModel(0)
        frames = [dataclasses.replace(f, detections=detector(f)) for f in scene.frames]
        best: dict[float, list[float]] = {}
        for _ in range(rounds):
            for i in intervals:
                run = time_scene(frames, configs[i])
                if i not in best or run[0] < best[i][0]:
                    best[i] = run
        for i in intervals:
            totals[i] = [a + b for a, b in zip(totals[i], best[i] + [len(frames)])]
    return totals


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="", help="comma-separated synthetic scenes (default: all)")
    parser.add_argument("--intervals", default="0", help="comma-separated orientation_interval_s values")
    parser.add_argument("--rounds", type=int, default=3, help="runs per scene and setting; the fastest is kept")
    parser.add_argument("--cpu", action="store_true", help="time this process's CPU time, not the wall time")
    args = parser.parse_args(argv)
    names = [n for n in args.scenes.split(",") if n] or list(SCENARIOS)
    intervals = [float(v) for v in args.intervals.split(",")]
    load = os.getloadavg()[0]
    install_clocks(args.cpu)
    totals = measure(names, intervals, max(args.rounds, 1))
    print(f"load: {load:.2f} before, {os.getloadavg()[0]:.2f} after (1-minute average); times in ms per frame"
          + (" of CPU" if args.cpu else ""))
    print("| orientation_interval_s | frames | pedestrians | update | behaviour | share of the rest | "
          "orientation | ego path + conflict | behaviour less ego path + conflict, share |")
    print("|---|---|---|---|---|---|---|---|---|")
    for i, (update, extra, orient, conflict, people, frames) in totals.items():
        rest = max(update - extra, 1e-12)
        print(f"| {i:g} | {frames:.0f} | {people / frames:.1f} | {1e3 * update / frames:.2f} | "
              f"{1e3 * extra / frames:.3f} | {100 * extra / rest:.1f} % | {1e3 * orient / frames:.3f} | "
              f"{1e3 * conflict / frames:.3f} | {100 * (extra - conflict) / rest:.1f} % |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
