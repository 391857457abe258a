"""Conflict events replayed with other readings of the ego's motion (issue 22): how much the ego's own path
limits "enters the corridor within 2 s".

    PYTHONPATH=src python benchmarks/behaviour_conflict_replay.py --seeds 0-7 --cache /tmp/conflict-rec
    PYTHONPATH=src python benchmarks/behaviour_conflict_replay.py --seeds 8-11 --variants now,oracle

Each seed runs ``benchmarks/behaviour.py``'s synthetic scenes once, recording what the conflict cue was
given (every ego pose; per frame the pedestrians' predicted positions (N, 2, K) and covariances (N, 3, K) at
the corridor's steps) and the benchmark's rows; the cue is then replayed with the ego's motion read in other
ways, the pedestrians' predictions unchanged. ``now`` is the estimator's own reading (it reproduces the
benchmark's figures). ``oracle`` takes the speed and yaw rate that carry the ego to its true pose 2 s later
(a constant turn): no reading of past poses can foresee more of a turn. The rest: ``last-pair``, the yaw
rate of the last two poses; ``line-0.3s``, a line fitted to the yaw rates of the last 0.3 s; ``widen-1s``,
the yaw rate's spread widened by 1 s times its fitted slope (the corridor widens while the turn changes);
``trend-0.25s``, the yaw rate moved 0.25 s along that slope.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import pickle
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import behaviour_synthetic as bench  # noqa: E402

import pedenv.behaviour.estimator as estimator  # noqa: E402
from pedenv.behaviour import ego_path  # noqa: E402
from pedenv.behaviour.config import BehaviourConfig  # noqa: E402
from pedenv.behaviour.conflict import CONFLICT_PROBABILITY, conflict_of  # noqa: E402
from pedenv.behaviour.ego_path import EgoHistory, EgoMotion, _clip, _fit_map, predict_ego_path  # noqa: E402
from pedenv.records import EgoPose  # noqa: E402


def record(seed: int) -> dict:
    """The benchmark's run of ``seed``: ego poses ``(t, x, y, yaw)``, conflict calls ``(pose index,
    positions, covariances)``, matches ``(call index, pedestrian indices)`` in the rows' order, and rows."""
    ego: list = []
    calls: list = []
    matches: list = []
    add, conflict, match = EgoHistory.add, estimator.conflict_of, bench.greedy_match

    def add_pose(self, timestamp, pose):
        ego.append((float(timestamp), float(pose.translation[0]), float(pose.translation[1]), float(pose.yaw)))
        return add(self, timestamp, pose)

    def conflict_call(path, steps, covariances, half_width, front):
        calls.append((len(ego) - 1, steps.copy(), covariances.copy()))
        return conflict(path, steps, covariances, half_width, front)

    def match_call(*args, **kwargs):
        pairs = match(*args, **kwargs)
        matches.append((len(calls) - 1, [int(d) for d, _ in pairs]))
        return pairs

    EgoHistory.add, estimator.conflict_of, bench.greedy_match = add_pose, conflict_call, match_call
    try:
        rows, _ = bench.synthetic_behaviour(seed)
    finally:
        EgoHistory.add, estimator.conflict_of, bench.greedy_match = add, conflict, match
    keep = [{k: r.get(k) for k in ("scene", "t", "true_event", "probability")} for r in rows]
    return {"ego": ego, "calls": calls, "matches": matches, "rows": keep}


def _rate_slope(h: EgoHistory) -> float:
    """The fitted yaw rate's slope now (rad/s^2), 0 with fewer than 3 pose pairs."""
    if len(h.pairs) < 3:
        return 0.0
    now = h.poses[-1][0]
    return float((_fit_map(tuple(round(p[0] - now, 6) for p in h.pairs)) @ [p[2] for p in h.pairs])[1])


def _oracle(h: EgoHistory, ego: list, i: int) -> EgoMotion:
    m = h.motion()
    if i + 20 >= len(ego) or abs(ego[i + 20][0] - ego[i][0] - 2.0) > 1e-6:
        return m  # no true future within the scene
    dist = sum(math.hypot(ego[j + 1][1] - ego[j][1], ego[j + 1][2] - ego[j][2]) for j in range(i, i + 20))
    turn = math.remainder(ego[i + 20][3] - ego[i][3], 2.0 * math.pi)
    return dataclasses.replace(m, speed=math.copysign(dist / 2.0, m.speed or 1.0), yaw_rate=turn / 2.0,
                               acceleration=0.0, jerk=0.0)


def _line(h: EgoHistory, window_s: float) -> EgoMotion:
    m, now = h.motion(), h.poses[-1][0]
    recent = [p for p in h.pairs if now - p[0] <= window_s]
    if len(recent) < 2:
        return m
    fit = np.polyfit([p[0] - now for p in recent], [p[2] for p in recent], 1)
    return dataclasses.replace(m, yaw_rate=_clip(float(fit[1]), ego_path.MAX_YAW_RATE_RADPS))


VARIANTS = {
    "now": lambda h, _ego, _i: h.motion(),
    "oracle": _oracle,
    "last-pair": lambda h, _ego, _i: (dataclasses.replace(h.motion(), yaw_rate=h.pairs[-1][2]) if h.pairs
                                      else h.motion()),
    "line-0.3s": lambda h, _ego, _i: _line(h, 0.3),
    "widen-1s": lambda h, _ego, _i: dataclasses.replace(
        h.motion(), yaw_rate_std=h.motion().yaw_rate_std + abs(_rate_slope(h))),
    "trend-0.25s": lambda h, _ego, _i: dataclasses.replace(
        h.motion(), yaw_rate=_clip(h.motion().yaw_rate + 0.25 * _rate_slope(h), ego_path.MAX_YAW_RATE_RADPS)),
}


def replay(rec: dict, cfg: BehaviourConfig, variant) -> np.ndarray:
    """The conflict probability of every row of ``rec`` with the ego's motion read by ``variant``."""
    times = np.linspace(0.0, cfg.conflict_horizon_s, int(round(cfg.conflict_horizon_s / estimator.CONFLICT_STEP_S)) + 1)
    h, probs, calls = EgoHistory(), [], iter(rec["calls"])
    call = next(calls, None)
    for i, (t, x, y, yaw) in enumerate(rec["ego"]):
        pose = EgoPose.from_xy_yaw(x, y, yaw)
        h.add(t, pose)  # a time that does not increase (the next scene) starts the history again
        while call is not None and call[0] == i:
            path = predict_ego_path(pose, variant(h, rec["ego"], i), times, ego_path.EGO_TREND_S,
                                    ego_path.MAX_EGO_ACCELERATION_MPS2)
            found = conflict_of(path, call[1], call[2], cfg.corridor_half_width_m, cfg.corridor_front_m)
            probs.append(found.probability)
            call = next(calls, None)
    return np.array([probs[c][d] for c, ds in rec["matches"] for d in ds])


def counts(rec: dict, probability: np.ndarray, threshold: float) -> np.ndarray:
    """(3,) int: hits, true events, predicted events over the rows with an ego future."""
    scored = np.array([r["true_event"] is not None for r in rec["rows"]])
    truth = np.array([bool(r["true_event"]) for r in rec["rows"]]) & scored
    predicted = (probability >= threshold) & scored
    return np.array([(truth & predicted).sum(), truth.sum(), predicted.sum()])


def _seeds(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-7", help="seeds: 0-7 or 8,9,10")
    parser.add_argument("--variants", default=",".join(VARIANTS))
    parser.add_argument("--thresholds", default="",
                        help="conflict probability thresholds (default: conflict.CONFLICT_PROBABILITY)")
    parser.add_argument("--cache", type=Path, default=None, help="folder for the recordings (reused when there)")
    args = parser.parse_args(argv)
    cfg = bench.Config().replace(behaviour={"horizons_s": list(bench.BENCH_HORIZONS)}).behaviour
    recs = {}
    for seed in _seeds(args.seeds):
        path = args.cache / f"seed{seed}.pkl" if args.cache else None
        if path is not None and path.exists():
            recs[seed] = pickle.loads(path.read_bytes())
            continue
        recs[seed] = record(seed)
        if path is not None:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(pickle.dumps(recs[seed]))
    thresholds = [float(v) for v in args.thresholds.split(",") if v] or [CONFLICT_PROBABILITY]
    print("| variant | threshold | " + " | ".join(f"seed {s}" for s in recs) + " | pooled: recall, precision |")
    print("|---|---|" + "---|" * len(recs) + "---|")
    for name in args.variants.split(","):
        probs = {s: replay(r, cfg, VARIANTS[name]) for s, r in recs.items()}
        for threshold in thresholds:
            per = [counts(r, probs[s], threshold) for s, r in recs.items()]
            hits, true, predicted = sum(per)
            print(f"| {name} | {threshold:g} | " + " | ".join("{}/{}/{}".format(*c) for c in per)
                  + f" | {100 * hits / max(true, 1):.1f} %, {100 * hits / max(predicted, 1):.1f} % |")
    print("\n(cells: hits / true events / predicted events)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
