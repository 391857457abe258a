"""CPU time of the behaviour cues alone, per frame: the synthetic scenes run once through the model
(``fused`` preset, as ``benchmarks/behaviour.py``) while every call of the behaviour estimator is
recorded; the recorded calls are then replayed through fresh estimators ``--repeat`` times and the
best process time (``time.process_time``, less disturbed by other jobs than the wall clock) is
printed, with the wall time of ``model.update`` in the first run for scale. Compare two trees by
running this file with each on ``PYTHONPATH``, alternating.

    PYTHONPATH=src python benchmarks/behaviour_cost.py
    PYTHONPATH=/tmp/beh-before/src python benchmarks/behaviour_cost.py --scenes red-light-crossing
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import os
import time

from behaviour_synthetic import BENCH_HORIZONS

from pedenv.behaviour.estimator import BehaviourEstimator
from pedenv.config import Config
from pedenv.model import PedestrianEnvironmentModel
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.detector import DetectorModel


def record(names: list[str], seed: int = 0) -> tuple[list[list[tuple]], float, int]:
    """Per scene the behaviour estimator's calls (deep copies of their arguments), the wall time
    of ``model.update`` over all frames (s) and the number of frames."""
    config = Config().replace(behaviour={"horizons_s": list(BENCH_HORIZONS)})
    scenes, wall, frames = [], 0.0, 0
    for scene in generate_scenes(seed, names):
        model, detector, calls = PedestrianEnvironmentModel(config), DetectorModel(seed), []
        estimator = model.behaviour
        assert estimator is not None, "the fused preset computes the behaviour cues"
        inner = estimator.update

        def recording(*args, inner=inner, calls=calls):
            calls.append(copy.deepcopy(args))
            return inner(*args)

        estimator.update = recording  # type: ignore[method-assign]
        for frame in scene.frames:
            frame = dataclasses.replace(frame, detections=detector(frame))
            start = time.perf_counter()
            model.update(frame)
            wall += time.perf_counter() - start
        scenes.append(calls)
        frames += len(scene.frames)
    return scenes, wall, frames


def replay(scenes: list[list[tuple]], config: Config) -> float:
    """Process time (s) of the behaviour cues over the recorded calls, fresh estimators per scene."""
    start = time.process_time()
    for calls in scenes:
        estimator = BehaviourEstimator(config.behaviour, config.kalman.acceleration_std_mps2)
        for args in calls:
            estimator.update(*args)
    return time.process_time() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="", help="comma-separated synthetic scenes (default: all)")
    parser.add_argument("--repeat", type=int, default=3, help="replays; the best is printed")
    args = parser.parse_args(argv)
    names = [n for n in args.scenes.split(",") if n] or list(SCENARIOS)
    scenes, wall, frames = record(names)
    config = Config().replace(behaviour={"horizons_s": list(BENCH_HORIZONS)})
    best = min(replay(scenes, config) for _ in range(max(args.repeat, 1)))
    n_peds = sum(len(call[1]) for calls in scenes for call in calls)
    print(f"load: {os.getloadavg()[0]:.2f} (1-minute average)")
    print(f"{frames} frames, {n_peds / max(frames, 1):.1f} pedestrians per frame: behaviour cues "
          f"{1e3 * best / max(frames, 1):.3f} ms CPU per frame (best of {args.repeat} replays); "
          f"model.update {1e3 * wall / max(frames, 1):.2f} ms wall per frame in the recording run")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
