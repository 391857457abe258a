"""How well can a walker's velocity be known from one camera? The predicted path's error at 2 s
on the synthetic scenes for other velocity estimates, and a floor no estimate can beat.

    PYTHONPATH=src python benchmarks/behaviour_velocity.py            # seed 0, all scenes

Each built-in scene runs through the model (``fused`` preset, default detector model); per track
the benchmark records every frame's measured ground point ``z`` (world x-y, m) and its
frame-to-frame covariance ``r`` (what :func:`pedenv.kalman.correct` receives), the track's
filtered velocity and the matched walker (IoU >= 0.5). Scored as in ``behaviour_synthetic.py``:
the mean "motion FDE 2 s", ``|2 s * v - (true position in 2 s - true position now)|``, against
the constant-velocity prediction from the true state (``CV``). Estimates, each from the
measurements up to now:

- ``filter``: the track's own Kalman filter (what pedenv reports);
- ``filter a=...``: the same filter run again on the recorded measurements with another
  acceleration noise (m/s^2), with the ``fused`` preset's restart gate;
- ``WLS W s``: a weighted least-squares line through the last W seconds of measurements;
- ``floor W s``: the Cramer-Rao bound of any unbiased estimate from the last W seconds
  ("track": all of it) for a walker at constant velocity, were the noise white with the
  covariances ``r`` pedenv reports: the expected ``|2 s * error|`` (200 draws per row; rows with
  a single measurement in the window have none and are left out);
- ``oracle direction, filter speed`` and ``filter direction, true speed``: half an oracle each,
  the filter's speed along the walker's true direction of the next 2 s, and the filter's
  direction at the true speed: what a perfect heading cue (or a perfect speed cue) would leave.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
from collections import defaultdict

import numpy as np

import pedenv.model
from pedenv import kalman
from pedenv.config import Config
from pedenv.model import PedestrianEnvironmentModel
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.detector import DetectorModel
from pedenv.synthetic.detector_fit import greedy_match, iou_matrix
from pedenv.synthetic.generator import scene_pedestrians

LIMITS_M = (15.0, 30.0, 1e9)


@contextlib.contextmanager
def recorded_measurements(store: dict):
    """While open, every :func:`pedenv.kalman.correct` of the model leaves its ``z`` and ``r`` in ``store``."""
    original = pedenv.model.kalman.correct

    def correct(x, P, started, z, r, spread, config):
        store.update(z=z.copy(), r=r.copy())
        return original(x, P, started, z, r, spread, config)

    pedenv.model.kalman.correct = correct
    try:
        yield store
    finally:
        pedenv.model.kalman.correct = original


def collect(seed: int) -> list[dict]:
    """Per track: ``rows`` of (t, z (2,), r (2, 2), filtered velocity (2,), distance m, walker or -1),
    and the scene's truth and end time."""
    tracks: list[dict] = []
    for scene in generate_scenes(seed, list(SCENARIOS)):
        truth = scene_pedestrians(seed, scene.name, scene.frames[-1].timestamp + 1.0 / 10.0 + 1e-9)
        model, detector, series = PedestrianEnvironmentModel(Config()), DetectorModel(seed), defaultdict(list)
        with recorded_measurements({}) as last:
            for frame in scene.frames:
                p = model.update(dataclasses.replace(frame, detections=detector(frame))).pedestrians
                gt = frame.ground_truth
                if not len(p):
                    continue
                walker = np.full(len(p), -1)
                if gt is not None and len(gt):
                    for d, g in greedy_match(iou_matrix(p.boxes, gt.boxes), np.ones(len(p)), 0.5):
                        walker[d] = int(gt.ids[g])
                for i, tid in enumerate(p.track_ids):
                    series[int(tid)].append((frame.timestamp, last["z"][i], last["r"][i], p.velocities[i, :2],
                                             float(p.distances[i]), int(walker[i])))
        tracks += [{"rows": rows, "truth": truth, "end": scene.frames[-1].timestamp} for rows in series.values()]
    return tracks


def refiltered(rows: list, acceleration_std: float, gate: float = 25.0) -> list[np.ndarray]:
    """The velocity (2,) after each row of the Kalman filter run again on the rows' measurements."""
    x = P = None
    out, last_t = [], 0.0
    for t, z, r, *_ in rows:
        if x is not None:
            x, P = kalman.predict(x, P, *kalman.transition(round(t - last_t, 6), acceleration_std))
        if np.isfinite(z).all():
            fresh = x is None or kalman.innovation_distance(x, P, z[None], r[None])[0] > gate
            x, P = kalman.initial_state(z[None], r[None], 2.0) if fresh else kalman.update(x, P, z[None], r[None])
        last_t = t
        out.append(np.zeros(2) if x is None else x[0, 1::2])
    return out


class Normals:
    """The normal equations of the line ``[x, vx, y, vy]`` through a track's measurements over any
    window, from prefix sums of ``W = r^-1``, ``W t``, ``W t^2`` and ``W z``, ``t W z`` (O(1) each)."""

    def __init__(self, rows: list) -> None:
        self.t = np.array([row[0] for row in rows])
        ok = np.array([np.isfinite(row[1]).all() and np.isfinite(row[2]).all() for row in rows])
        w = np.array([np.linalg.inv(row[2]) if k else np.zeros((2, 2)) for row, k in zip(rows, ok)])
        wz = np.einsum("nij,nj->ni", w, np.array([np.where(k, row[1], 0.0) for row, k in zip(rows, ok)]))
        t = self.t[:, None, None]
        self.w = [np.concatenate([np.zeros((1, 2, 2)), np.cumsum(w * t**k, axis=0)]) for k in range(3)]
        self.wz = [np.concatenate([np.zeros((1, 2)), np.cumsum(wz * self.t[:, None] ** k, axis=0)]) for k in range(2)]
        self.count = np.concatenate([[0], np.cumsum(ok)])

    def at(self, i: int, window_s: float) -> tuple[np.ndarray, np.ndarray, int]:
        """Normal matrix (4, 4), vector (4,) at row i's time, and the number of measurements, over
        the last ``window_s`` seconds."""
        t = self.t[i]
        j = int(np.searchsorted(self.t, t - window_s - 1e-6))
        s0, s1, s2 = (m[i + 1] - m[j] for m in self.w)
        z0, z1 = (m[i + 1] - m[j] for m in self.wz)
        m1, m2 = s1 - t * s0, s2 - 2.0 * t * s1 + t * t * s0  # the moments in (th - t)
        A, b = np.zeros((4, 4)), np.zeros(4)
        p, v = [0, 2], [1, 3]
        A[np.ix_(p, p)], A[np.ix_(p, v)], A[np.ix_(v, p)], A[np.ix_(v, v)] = s0, m1, m1, m2
        b[p], b[v] = z0, z1 - t * z0
        return A, b, int(self.count[i + 1] - self.count[j])


def least_squares(rows: list, window_s: float) -> list[np.ndarray]:
    """The velocity (2,) of the weighted line through each row's last ``window_s`` seconds (the
    filter's where fewer than 3 measurements span 0.25 s)."""
    normals, out = Normals(rows), []
    for i, row in enumerate(rows):
        A, b, n = normals.at(i, window_s)
        first = normals.t[int(np.searchsorted(normals.t, row[0] - window_s - 1e-6))]
        out.append(np.linalg.solve(A, b)[1::2] if n >= 3 and row[0] - first >= 0.25 else row[3])
    return out


def floor(rows: list, window_s: float, rng: np.random.Generator) -> list[float]:
    """Per row: the expected ``|2 s * velocity error|`` (m) at the Cramer-Rao bound (white noise ``r``)."""
    normals, out = Normals(rows), []
    for i in range(len(rows)):
        A, _, n = normals.at(i, window_s)
        if n < 2:  # one measurement: no velocity, no bound
            out.append(np.nan)
            continue
        try:
            cov = 4.0 * np.linalg.inv(A)[np.ix_([1, 3], [1, 3])]
            draws = rng.standard_normal((200, 2)) @ np.linalg.cholesky(cov + 1e-12 * np.eye(2)).T
            out.append(float(np.linalg.norm(draws, axis=1).mean()))
        except np.linalg.LinAlgError:  # too few measurements: no bound
            out.append(np.nan)
    return out


def scored_rows(track: dict) -> list[tuple[int, float, np.ndarray, float]]:
    """(row index, distance m, true displacement over 2 s (2,), CV-from-truth error m) of each row
    matched to a walker whose next 2 s lie in the scene."""
    out, truth = [], track["truth"]
    for i, (t, _, _, _, dist, g) in enumerate(track["rows"]):
        if g < 0 or t + 2.0 > track["end"] + 1e-9:
            continue
        moved = truth.at(t + 2.0).xy[g] - truth.at(t).xy[g]
        velocity = (truth.at(t + 0.05).xy[g] - truth.at(t - 0.05).xy[g]) / 0.1
        out.append((i, dist, moved, float(np.linalg.norm(2.0 * velocity - moved))))
    return out


def half_oracles(rows: list, scored: list) -> dict[str, list[tuple[float, float]]]:
    """Per half oracle: (distance m, FDE at 2 s m) of each scored row (see the module's docstring)."""
    out: dict[str, list[tuple[float, float]]] = {"oracle direction, filter speed": [],
                                                 "filter direction, true speed": []}
    for i, d, moved, _ in scored:
        v = np.asarray(rows[i][3], float)
        true_direction = moved / max(float(np.linalg.norm(moved)), 1e-9)
        own_direction = v / max(float(np.linalg.norm(v)), 1e-9)
        out["oracle direction, filter speed"].append(
            (d, float(np.linalg.norm(2.0 * np.linalg.norm(v) * true_direction - moved))))
        out["filter direction, true speed"].append(
            (d, float(np.linalg.norm(np.linalg.norm(moved) * own_direction - moved))))
    return out


def table(tracks: list[dict]) -> dict[str, np.ndarray]:
    """Per estimate: (R, 2) distance and error (m) of every scored row."""
    rng, results = np.random.default_rng(0), defaultdict(list)
    estimates = {"filter": lambda rows: [r[3] for r in rows],
                 **{f"filter a={a:g}": (lambda rows, a=a: refiltered(rows, a)) for a in (1.0, 0.3, 0.1)},
                 **{f"WLS {w:g} s": (lambda rows, w=w: least_squares(rows, w)) for w in (1.0, 2.0, 3.0)}}
    for track in tracks:
        scored = scored_rows(track)
        if not scored:
            continue
        rows = track["rows"]
        results["CV from the true state"] += [(d, cv) for _, d, _, cv in scored]
        for name, pairs in half_oracles(rows, scored).items():
            results[name] += pairs
        for name, estimate in estimates.items():
            v = estimate(rows)
            results[name] += [(d, float(np.linalg.norm(2.0 * v[i] - moved))) for i, d, moved, _ in scored]
        for w, label in ((2.0, "floor 2 s"), (1e9, "floor track")):
            bound = floor(rows, w, rng)
            results[label] += [(d, bound[i]) for i, d, _, _ in scored]
    return {k: np.array(v) for k, v in results.items()}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    results = table(collect(args.seed))
    cv = results["CV from the true state"]
    print("| velocity estimate | " + " | ".join(f"within {lim:g} m" if lim < 1e8 else "all" for lim in LIMITS_M)
          + " |\n|---|" + "---|" * len(LIMITS_M))
    for name, e in results.items():
        cells = []
        for lim in LIMITS_M:
            sel, base = e[e[:, 0] <= lim, 1], cv[cv[:, 0] <= lim, 1].mean()
            cells.append(f"{np.nanmean(sel):.2f} m ({np.nanmean(sel) / base:.1f}x)")
        print(f"| {name} | " + " | ".join(cells) + " |")
    print(f"\nrows: {len(cv)} (within 15 m: {(cv[:, 0] <= 15).sum()}, within 30 m: {(cv[:, 0] <= 30).sum()})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
