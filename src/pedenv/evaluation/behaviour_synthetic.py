"""Behaviour cues on the synthetic scenes, against the scenes' own truth (``benchmarks/behaviour.py``
prints the tables; ``tests/behaviour/test_measured_figures.py`` checks them).

Each built-in scene (seed 0) runs through the model (``fused`` preset, detector model of
``profile``) with the predicted path sampled every 0.25 s up to 2 s. Every reported pedestrian
whose box matches a true one (IoU >= 0.5) is scored against the walker's plan
(:func:`pedenv.synthetic.generator.scene_pedestrians`): its facing, its true position 0.25 .. 2 s
later (for ADE/FDE; the baseline is the constant-velocity prediction from the true position and
velocity), its true motion (standing or walking), and whether it truly enters the corridor
around the ego's true future path within 2 s (the same corridor as the estimator's: the ego's
path over the horizon plus ``corridor_front_m``, ``corridor_half_width_m`` either side). An
event is also scored apart when the ego's turn only begins after now (its true yaw rate is below
:data:`STRAIGHT_RADPS` now and above :data:`TURNING_RADPS` within the horizon): no estimate from
its poses can foresee it.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.behaviour.conflict import CONFLICT_PROBABILITY
from pedenv.config import Config
from pedenv.geometry import wrap_angle
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Scene
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.detector import DetectorModel
from pedenv.synthetic.detector_fit import greedy_match, iou_matrix
from pedenv.synthetic.generator import scene_pedestrians

#: Horizons of the benchmark's predicted path (s): ADE over the first four is ADE at 1 s.
BENCH_HORIZONS = (0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0)
#: The ego drives straight below this yaw rate (rad/s) and turns above the other.
STRAIGHT_RADPS, TURNING_RADPS = 0.02, 0.05


def true_entry(ego_xy: np.ndarray, ego_yaw: float, ped_xy: np.ndarray, cfg: BehaviourConfig) -> float:
    """First time index (into the K samples) at which the pedestrian's true positions ``ped_xy`` (K, 2)
    lie within ``corridor_half_width_m`` of the ego's true path ``ego_xy`` (K, 2) extended by
    ``corridor_front_m`` along ``ego_yaw`` (radians, at the end); -1 if never."""
    ext = ego_xy[-1] + np.linspace(0.0, cfg.corridor_front_m, 12)[1:, None] * [np.cos(ego_yaw), np.sin(ego_yaw)]
    line = np.concatenate([ego_xy, ext])
    seg = np.linalg.norm(np.diff(line, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    fine = np.linspace(0.0, s[-1], max(int(s[-1] / 0.05), 1) + 1)
    dense = np.column_stack([np.interp(fine, s, line[:, 0]), np.interp(fine, s, line[:, 1])])
    d = np.linalg.norm(ped_xy[:, None] - dense[None], axis=2)
    nearest = d.argmin(axis=1)
    inside = (d.min(axis=1) < cfg.corridor_half_width_m)
    if len(dense) > 1:  # not beyond the start (behind the ego)
        inside &= ~((nearest == 0) & ((ped_xy - dense[0]) @ (dense[1] - dense[0]) < 0))
    hits = np.flatnonzero(inside)
    return int(hits[0]) if len(hits) else -1


def run_scene(scene: Scene, seed: int, profile: str | None, config: Config, rows: list, timing: dict) -> None:
    """Run one scene and append one row per matched pedestrian and frame to ``rows``."""
    truth = scene_pedestrians(seed, scene.name, scene.frames[-1].timestamp + 1.0 / 10.0 + 1e-9)
    model = PedestrianEnvironmentModel(config)
    detector = DetectorModel(seed, profile=profile)
    cfg = config.behaviour
    times = np.array([f.timestamp for f in scene.frames])
    yaws = np.unwrap([f.ego.yaw for f in scene.frames])
    rates = np.abs(np.gradient(yaws, times)) if len(times) > 1 else np.zeros(len(times))
    step = int(round(cfg.conflict_horizon_s * 10))
    for k, frame in enumerate(scene.frames):
        frame = dataclasses.replace(frame, detections=detector(frame))
        start = time.perf_counter()
        state = model.update(frame)
        timing["update_s"] += time.perf_counter() - start
        timing["frames"] += 1
        timing["pedestrians"] += len(state.pedestrians)
        gt, p = frame.ground_truth, state.pedestrians
        if gt is None or not len(gt) or not len(p):
            continue
        pairs = greedy_match(iou_matrix(p.boxes, gt.boxes), np.ones(len(p)), 0.5)
        t = frame.timestamp
        now = truth.at(t)
        before, after = truth.at(t - 0.05), truth.at(t + 0.05)
        future = np.stack([truth.at(t + h).xy for h in BENCH_HORIZONS], axis=1)  # (P, H, 2)
        ego_future = k + step < len(scene.frames)
        if ego_future:
            ego_xy = np.array([f.ego.translation[:2] for f in scene.frames[k:k + step + 1]])
            ped_path = np.stack([truth.at(s).xy for s in times[k:k + step + 1]], axis=1)
        b = p.behaviour
        assert b is not None, "the fused preset estimates behaviour"
        for d, g in pairs:
            gid = int(gt.ids[g])
            velocity = (after.xy[gid] - before.xy[gid]) / 0.1
            row = {"scene": scene.name, "distance_m": float(p.distances[d]), "t": t, "gid": gid,
                   "probability": float(b.conflict_probability[d]),
                   "yaw_error_deg": float(np.degrees(abs(wrap_angle(b.yaw[d] - now.heading[gid])))),
                   "available": int(b.orientation_availability[d]),
                   "true_moving": bool(now.moving[gid]), "state": int(b.motion_state[d]),
                   "speed": float(b.speed[d]), "speed_std": float(b.speed_std[d]),
                   "in_scene_2s": bool(t + 2.0 <= times[-1])}
            row["pred_err"] = np.linalg.norm(b.predicted_positions[d] - future[gid], axis=1)
            moved = b.predicted_positions[d] - p.positions[d, :2]  # the predicted motion alone
            row["motion_err"] = np.linalg.norm(moved - (future[gid] - now.xy[gid]), axis=1)
            cv = now.xy[gid] + np.asarray(BENCH_HORIZONS)[:, None] * velocity
            row["cv_err"] = np.linalg.norm(cv - future[gid], axis=1)
            if ego_future:
                entry = true_entry(ego_xy, float(scene.frames[k + step].ego.yaw), ped_path[gid], cfg)
                row.update(true_event=entry >= 0, true_time=entry / 10.0 if entry >= 0 else None,
                           predicted_event=bool(b.conflict_probability[d] >= CONFLICT_PROBABILITY),
                           predicted_time=float(b.conflict_time[d]),
                           turn_ahead=bool(rates[k] < STRAIGHT_RADPS and rates[k:k + step + 1].max() > TURNING_RADPS))
            rows.append(row)
    timing["behaviour_s"] += model.behaviour.elapsed_s if model.behaviour is not None else 0.0


def synthetic_behaviour(seed: int = 0, profile: str | None = None, names: list[str] | None = None,
                        duration_s: float | None = None, terrain: bool = False) -> tuple[list[dict], dict]:
    """Rows (one per matched pedestrian and frame) and the timing of the run."""
    config = Config().replace(behaviour={"horizons_s": list(BENCH_HORIZONS)})
    rows: list[dict] = []
    timing = {"update_s": 0.0, "behaviour_s": 0.0, "frames": 0, "pedestrians": 0}
    for scene in generate_scenes(seed, names or list(SCENARIOS), duration_s=duration_s, terrain=terrain):
        run_scene(scene, seed, profile, config, rows, timing)
    return rows, timing
