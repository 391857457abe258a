"""Behaviour cues against the labelled future: ``metrics.json``'s ``behaviour``.

Per labelled frame, each reported pedestrian paired one-to-one with a labelled one
(:func:`pedenv.evaluation.matching.match_one_to_one`, box IoU at least 0.5) is scored once the
scene has ended, against where that labelled person really is later:

- ``fde_1s_m``, ``fde_2s_m``, ``fde_3s_m``: mean distance between the predicted position at
  that horizon (``behaviour.predicted_positions``) and the labelled position then, over the
  pairs still labelled at the horizon; ``fde_*_constant_velocity_m`` the same for pedenv's own
  position and velocity carried forward (the baseline; the only figure without behaviour cues);
- motion state against the labelled speed (the centred difference of the labelled positions
  over :data:`SPEED_HALF_WINDOW_S` either side): standing below :data:`STANDING_MPS`, running
  above :data:`RUNNING_MPS`: agreement and a confusion table (rows labelled, columns reported);
- conflict within ``conflict_horizon_s``: whether the labelled person enters the corridor
  (``corridor_half_width_m`` either side) of the ego's real path over the horizon, extended
  ``corridor_front_m`` ahead, against ``conflict_probability`` at or above the shipped
  threshold (``behaviour.conflict.CONFLICT_PROBABILITY``): recall and precision. A person who stops being
  labelled before the horizon (out of view: passed beside or behind the car) is judged on the
  labelled part (counted as ``partial_future``); one with no later label at all, or whose ego
  poses end before the horizon, is not scored (``unknown``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.behaviour.motion_state import MOTION_STATE_NAMES
from pedenv.evaluation.matching import match_one_to_one
from pedenv.records import Frame
from pedenv.state import EnvironmentState

#: The horizons scored (s); each must be one of the predicted path's.
FDE_HORIZONS_S = (1.0, 2.0, 3.0)
#: The issue's bounds of the labelled speed: standing below, running above (m/s).
STANDING_MPS, RUNNING_MPS = 0.3, 2.5
#: Half the window of the labelled speed's centred difference (s): labels jitter by 5-30 cm.
SPEED_HALF_WINDOW_S = 0.5
_KEY = 100.0  # timestamps as integer keys in hundredths of a second (10 Hz frames)


@dataclass
class BehaviourSamples:
    """One scene's scored pairs (each list one entry per pair, arrays once finished)."""

    fde: dict[str, list] = field(default_factory=dict)  # "1s", "1s_cv", ... -> errors (m)
    state_reported: list = field(default_factory=list)
    state_labelled: list = field(default_factory=list)
    conflict_probability: list = field(default_factory=list)
    conflict_labelled: list = field(default_factory=list)
    conflict_unknown: int = 0
    conflict_partial: int = 0


@dataclass
class _Pair:
    key: int
    gt_id: int
    cv: np.ndarray  # (2,) position, (2,) velocity
    predicted: np.ndarray | None  # (H, 2) or None
    state: int
    conflict: float


class BehaviourRecorder:
    """Collects one scene's frames (:meth:`add`) and scores them at its end (:meth:`finish`)."""

    def __init__(self, config: BehaviourConfig) -> None:
        self.config = config
        self.truth: dict[tuple[int, int], np.ndarray] = {}  # (time key, id) -> labelled x-y
        self.ego: dict[int, np.ndarray] = {}  # time key -> ego x, y, yaw
        self.pairs: list[_Pair] = []

    def add(self, frame: Frame, state: EnvironmentState) -> None:
        gt, peds = frame.ground_truth, state.pedestrians
        if gt is None or (len(gt) and np.any(gt.ids < 0)):
            return
        key = int(round(frame.timestamp * _KEY))
        self.ego[key] = np.r_[frame.ego.translation[:2], frame.ego.yaw]
        for i, xy in zip(gt.ids.tolist(), gt.positions[:, :2]):
            self.truth[(key, i)] = xy
        same = match_one_to_one(peds.boxes, gt.boxes)
        b = peds.behaviour
        for row in np.flatnonzero(same >= 0):
            predicted, state_code, conflict = None, -1, float("nan")
            if b is not None:
                predicted = self._at(b.predicted_positions[row], np.asarray(b.horizons, float))
                state_code, conflict = int(b.motion_state[row]), float(b.conflict_probability[row])
            cv = np.r_[peds.positions[row, :2], peds.velocities[row, :2]]
            self.pairs.append(_Pair(key, int(gt.ids[same[row]]), cv, predicted, state_code, conflict))

    @staticmethod
    def _at(predicted: np.ndarray, horizons: np.ndarray) -> np.ndarray:
        """(len(FDE_HORIZONS_S), 2) predicted positions at the scored horizons (NaN where not predicted)."""
        out = np.full((len(FDE_HORIZONS_S), 2), np.nan)
        for k, h in enumerate(FDE_HORIZONS_S):
            hit = np.flatnonzero(np.abs(horizons - h) < 1e-6)
            if len(hit):
                out[k] = predicted[hit[0]]
        return out

    def finish(self) -> BehaviourSamples:
        """The scene's scored pairs."""
        out = BehaviourSamples()
        for h in FDE_HORIZONS_S:
            out.fde[f"{h:g}s"], out.fde[f"{h:g}s_cv"] = [], []
        step = int(round(self.config.conflict_horizon_s * _KEY))
        for p in self.pairs:
            for k, h in enumerate(FDE_HORIZONS_S):
                later = self.truth.get((p.key + int(round(h * _KEY)), p.gt_id))
                if later is None:
                    continue
                out.fde[f"{h:g}s_cv"].append(float(np.linalg.norm(p.cv[:2] + h * p.cv[2:] - later)))
                if p.predicted is not None and np.isfinite(p.predicted[k]).all():
                    out.fde[f"{h:g}s"].append(float(np.linalg.norm(p.predicted[k] - later)))
            speed = self._labelled_speed(p.key, p.gt_id)
            if p.state >= 0 and speed is not None:
                out.state_reported.append(p.state)
                out.state_labelled.append(int(speed >= STANDING_MPS) + int(speed > RUNNING_MPS))
            if p.state >= 0:
                entered, partial = self._enters(p.key, p.gt_id, step)
                if entered is None:
                    out.conflict_unknown += 1
                else:
                    out.conflict_probability.append(p.conflict)
                    out.conflict_labelled.append(entered)
                    out.conflict_partial += partial
        return out

    def _labelled_speed(self, key: int, gt_id: int) -> float | None:
        half = int(round(SPEED_HALF_WINDOW_S * _KEY))
        before, after = self.truth.get((key - half, gt_id)), self.truth.get((key + half, gt_id))
        if before is None or after is None:
            return None
        return float(np.linalg.norm(after - before) / (2 * SPEED_HALF_WINDOW_S))

    def _enters(self, key: int, gt_id: int, step: int) -> tuple[bool | None, bool]:
        """Whether the labelled person enters the corridor of the ego's real path within the horizon
        (None: cannot be told), and whether that was judged on part of the horizon only."""
        keys = [k for k in range(key, key + step + 1, 10) if k in self.ego]
        if len(keys) < step // 10 + 1:
            return None, False
        ego = np.array([self.ego[k] for k in keys])
        person = [xy for k in keys[1:] if (xy := self.truth.get((k, gt_id))) is not None]
        if not person:
            return None, False
        cfg = self.config
        yaw = ego[-1, 2]
        ahead = ego[-1, :2] + np.linspace(0.0, cfg.corridor_front_m, 12)[1:, None] * [np.cos(yaw), np.sin(yaw)]
        line = _dense(np.concatenate([ego[:, :2], ahead]))
        for xy in person:
            d = np.linalg.norm(line - xy, axis=1)
            nearest = int(d.argmin())
            behind = nearest == 0 and len(line) > 1 and float((xy - line[0]) @ (line[1] - line[0])) < 0
            if d[nearest] < cfg.corridor_half_width_m and not behind:
                return True, False
        return False, len(person) < len(keys) - 1


def _dense(line: np.ndarray, spacing_m: float = 0.05) -> np.ndarray:
    """The polyline ``line`` (K, 2) resampled every ``spacing_m`` metres."""
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(line, axis=0), axis=1))])
    fine = np.linspace(0.0, s[-1], max(int(s[-1] / spacing_m), 1) + 1)
    return np.column_stack([np.interp(fine, s, line[:, 0]), np.interp(fine, s, line[:, 1])])


def behaviour_summary(samples: list[BehaviourSamples], threshold: float) -> dict:
    """The figures of the module doc over ``samples`` (scenes) together."""
    out: dict = {}
    fde = {k: np.concatenate([np.asarray(s.fde.get(k, []), float) for s in samples]) for k in samples[0].fde}
    for h in FDE_HORIZONS_S:
        pred, cv = fde.get(f"{h:g}s", np.zeros(0)), fde.get(f"{h:g}s_cv", np.zeros(0))
        out[f"fde_{h:g}s_m"] = float(pred.mean()) if len(pred) else None
        out[f"fde_{h:g}s_constant_velocity_m"] = float(cv.mean()) if len(cv) else None
        out[f"fde_{h:g}s_count"] = int(len(cv))
    reported = np.concatenate([np.asarray(s.state_reported, int) for s in samples])
    labelled = np.concatenate([np.asarray(s.state_labelled, int) for s in samples])
    if len(reported):
        table = np.zeros((3, 3), int)
        np.add.at(table, (labelled, reported), 1)
        out["motion_state"] = {"agreement": float(np.mean(reported == labelled)), "count": int(len(reported)),
                               "labelled_bounds_mps": [STANDING_MPS, RUNNING_MPS],
                               "confusion": {n: dict(zip(MOTION_STATE_NAMES, map(int, table[i])))
                                             for i, n in enumerate(MOTION_STATE_NAMES)}}
    prob = np.concatenate([np.asarray(s.conflict_probability, float) for s in samples])
    truth = np.concatenate([np.asarray(s.conflict_labelled, bool) for s in samples])
    if len(prob):
        flagged = prob >= threshold
        hits = int((flagged & truth).sum())
        out["conflict"] = {"threshold": threshold, "labelled_entries": int(truth.sum()), "flagged": int(flagged.sum()),
                           "recall": hits / truth.sum() if truth.any() else None,
                           "precision": hits / flagged.sum() if flagged.any() else None, "count": int(len(prob)),
                           "unknown": int(sum(s.conflict_unknown for s in samples)),
                           "partial_future": int(sum(s.conflict_partial for s in samples))}
    return out


#: The prefix of a scene's behaviour samples among a checkpoint's arrays (:mod:`pedenv.apps.scene_checkpoint`).
ARRAY_PREFIX = "behaviour_samples."
_LISTS = ("state_reported", "state_labelled", "conflict_probability", "conflict_labelled")


def samples_to_arrays(samples: BehaviourSamples) -> dict[str, np.ndarray]:
    """``samples`` as named plain arrays (no pickle), for a scene's checkpoint."""
    out = {f"{ARRAY_PREFIX}fde.{k}": np.asarray(v, np.float64) for k, v in samples.fde.items()}
    out.update({f"{ARRAY_PREFIX}{k}": np.asarray(getattr(samples, k), np.float64) for k in _LISTS})
    out[f"{ARRAY_PREFIX}counts"] = np.array([samples.conflict_unknown, samples.conflict_partial], np.int64)
    return out


def samples_from_arrays(arrays: dict[str, np.ndarray]) -> BehaviourSamples | None:
    """The samples :func:`samples_to_arrays` wrote, or None when ``arrays`` hold none."""
    if f"{ARRAY_PREFIX}counts" not in arrays:
        return None
    start = f"{ARRAY_PREFIX}fde."
    fde = {k[len(start):]: np.asarray(v, np.float64).tolist() for k, v in arrays.items() if k.startswith(start)}
    lists = {k: np.asarray(arrays[f"{ARRAY_PREFIX}{k}"], np.float64).tolist() for k in _LISTS}
    unknown, partial = (int(c) for c in np.asarray(arrays[f"{ARRAY_PREFIX}counts"], np.int64)[:2])
    return BehaviourSamples(fde, [int(s) for s in lists["state_reported"]], [int(s) for s in lists["state_labelled"]],
                            lists["conflict_probability"], [bool(c) for c in lists["conflict_labelled"]], unknown,
                            partial)
