"""One frame of the behaviour cues: the model calls :meth:`BehaviourEstimator.update` after localisation.

Per-track state (the heading distribution, the motion state, when it was last updated) lives
in :class:`TrackStore`, keyed by track id; tracks the tracker has dropped are forgotten.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time

import numpy as np

from pedenv.behaviour import facing, heading_filter, motion_state
from pedenv.behaviour.config import BehaviourConfig
from pedenv.behaviour.conflict import CORRIDOR_ACCELERATION_STD_MPS2, conflict_of
from pedenv.behaviour.ego_path import EGO_TREND_S, MAX_EGO_ACCELERATION_MPS2, EgoHistory, EgoPath, predict_ego_path
from pedenv.behaviour.motion_state import VelocityStats, velocity_stats
from pedenv.behaviour.orientation import CUE_KEYPOINTS, cue_from_rays, cue_likelihood, keypoint_rays, walking_likelihood
from pedenv.behaviour.prediction import JointPredictor, PathPredictor
from pedenv.geometry import inverse_intrinsics
from pedenv.records import Frame
from pedenv.state import Behaviour, Pedestrians


class TrackStore:
    """Per track id: ``p (T, B)`` heading distribution, ``time (T,)`` seconds of its last update
    (a new track's grid is flat, dated to the last orientation so that the tracks share one
    prediction step), ``state (T,)`` int8 motion state, and the orientation last computed
    (:meth:`BehaviourEstimator._orient`): ``held (4, T)`` the yaw (radians, world), its spread
    (radians) and the body's and the head's facing probability, ``available (T,)`` int8. A new
    track holds ``flat`` (4,), the values of the flat grid, and ``UNAVAILABLE`` until then. Rows
    are in the order the tracks came; ``index`` maps a track id to its row."""

    def __init__(self, bins: int, flat: np.ndarray) -> None:
        self.bins, self.flat = bins, flat
        self.clear()

    def clear(self) -> None:
        self.ids = np.zeros(0, np.int64)
        self.p = np.zeros((0, self.bins))
        self.state = np.zeros(0, np.int8)
        self.time = np.zeros(0)
        self.held = np.zeros((4, 0))
        self.available = np.zeros(0, np.int8)
        self.index: dict[int, int] = {}

    def rows(self, ids: np.ndarray, now: float) -> np.ndarray:
        """(N,) the rows of ``ids`` (N,), new ones added flat, standing, last updated ``now`` (s)."""
        index, keys = self.index, ids.tolist()
        try:
            return np.array([index[i] for i in keys], np.intp)
        except KeyError:
            pass
        new = sorted({i for i in keys if i not in index})
        for i in new:
            index[i] = len(index)
        m = len(new)
        self.ids = np.concatenate([self.ids, np.array(new, np.int64)])
        self.p = np.concatenate([self.p, heading_filter.uniform(m, self.bins)])
        self.state = np.concatenate([self.state, np.zeros(m, np.int8)])
        self.time = np.concatenate([self.time, np.full(m, now)])
        self.held = np.concatenate([self.held, np.repeat(self.flat[:, None], m, axis=1)], axis=1)
        self.available = np.concatenate([self.available, np.full(m, heading_filter.UNAVAILABLE, np.int8)])
        return np.array([index[i] for i in keys], np.intp)

    def keep(self, live_ids: np.ndarray) -> None:
        """Forget every track not in ``live_ids`` (checked once the store holds more rows than there
        are live tracks: a dropped track may wait a few frames)."""
        if len(self.ids) <= len(live_ids):
            return
        mask = ((self.ids[:, None] == live_ids).any(axis=1) if len(self.ids) * len(live_ids) < 4096
                else np.isin(self.ids, live_ids))
        if not mask.all():
            self.ids, self.p, self.state, self.time = self.ids[mask], self.p[mask], self.state[mask], self.time[mask]
            self.held, self.available = self.held[:, mask], self.available[mask]
            self.index = {i: row for row, i in enumerate(self.ids.tolist())}


class BehaviourEstimator:
    """The behaviour cues of every tracked pedestrian, frame by frame (``config``: ``Config.behaviour``;
    ``acceleration_std``: the Kalman filter's, m/s^2, for the predicted path)."""

    def __init__(self, config: BehaviourConfig, acceleration_std: float) -> None:
        self.config = config
        self.acceleration_std = acceleration_std
        self.ego = EgoHistory()
        self.grid = heading_filter.grid(config.orientation_bins)  # the trig and Fourier tables, once
        self.cells = self.grid.cells
        self.angles = (math.radians(HEADING_RANDOM_WALK_DEG), math.radians(config.available_std_deg),
                       math.radians(config.facing_half_angle_deg))  # random walk, available spread, facing
        flat_yaw, flat_std, _ = heading_filter.summary(heading_filter.uniform(1, config.orientation_bins), 1.0)
        self.store = TrackStore(config.orientation_bins, np.array([flat_yaw[0], flat_std[0],
                                                                   self.angles[2] / math.pi, 0.0]))
        self.oriented_at = -math.inf  # when the heading grids were last updated (``orientation_interval_s``)
        self.horizons = np.asarray(config.horizons_s, float)
        k = int(round(config.conflict_horizon_s / CONFLICT_STEP_S))
        self.conflict_times = np.linspace(0.0, k * CONFLICT_STEP_S, k + 1)
        self.predictor = JointPredictor(PathPredictor(self.horizons, acceleration_std),  # the path reported
                                        PathPredictor(self.conflict_times, CORRIDOR_ACCELERATION_STD_MPS2))  # corridor
        self.elapsed_s, self.frames = 0.0, 0  # wall time spent here, for ``benchmarks/behaviour.py``
        self._intrinsics: tuple[bytes, np.ndarray] = (b"", np.eye(3))  # the last camera's and their inverse

    def _inverse_intrinsics(self, frame: Frame) -> np.ndarray:
        """The inverse of the frame's camera matrix, computed again only when it changes."""
        key = frame.camera.intrinsics.tobytes()
        if key != self._intrinsics[0]:
            self._intrinsics = (key, inverse_intrinsics(frame.camera.intrinsics))
        return self._intrinsics[1]

    def reset(self) -> None:
        self.store.clear()
        self.ego.reset()
        self.oriented_at = -math.inf

    def update(self, frame: Frame, peds: Pedestrians, x: np.ndarray, P: np.ndarray, started: np.ndarray,
               live_ids: np.ndarray) -> Pedestrians:
        """``peds`` with their :class:`~pedenv.state.Behaviour`.

        x (N, 4), P (N, 4, 4): the pedestrians' Kalman states ``[x, vx, y, vy]`` (world, m and
        m/s) and covariances; started (N,) bool: the filter holds a state (elsewhere the
        reported position, standing, with a 2 m/s velocity spread; so is a row whose state is not
        finite or beyond :data:`STATE_LIMIT`); live_ids: every track id the tracker still holds.
        """
        start = time.perf_counter()
        # sums of squares below the squared limits bound every entry (False for NaN, inf and overflow);
        # otherwise the rows are checked one by one (the same x, P where all are usable)
        if len(peds) and not (started.all() and np.vdot(x, x) < STATE_LIMIT[0] ** 2
                              and np.vdot(P, P) < STATE_LIMIT[1] ** 2):
            x, P = _usable_states(peds, x, P, started)
        self.ego.add(frame.timestamp, frame.ego)
        path = predict_ego_path(self.ego.poses[-1][1:], self.ego.motion(), self.conflict_times, EGO_TREND_S,
                                MAX_EGO_ACCELERATION_MPS2)
        self.store.keep(live_ids)
        if len(peds) == 0:
            beh = dataclasses.replace(Behaviour.empty(self.horizons), conflict_horizon=float(self.conflict_times[-1]),
                                      ego_speed=path.motion.speed, ego_yaw_rate=path.motion.yaw_rate, ego_path=path.xy)
        else:
            beh = self._cues(frame, peds, x, P, path)
        self.elapsed_s, self.frames = self.elapsed_s + time.perf_counter() - start, self.frames + 1
        out = copy.copy(peds)  # dataclasses.replace, without its per-field work
        object.__setattr__(out, "behaviour", beh)
        return out

    def _cues(self, frame: Frame, peds: Pedestrians, x: np.ndarray, P: np.ndarray, path: EgoPath) -> Behaviour:
        cfg, t, store = self.config, frame.timestamp, self.store
        rows = store.rows(peds.track_ids, self.oriented_at if self.oriented_at > -math.inf else t)
        velocity = velocity_stats(x[:, 1::2], P[:, 1::2, 1::2])
        if not 0.0 <= t - self.oriented_at < cfg.orientation_interval_s - REFRESH_TOLERANCE_S:
            self._orient(frame, peds, rows, velocity)
            self.oriented_at = t
        held = store.held[:, rows]
        speed, speed_std = motion_state.speed_from(velocity)
        median, mean, corridor = motion_state.speed_posterior(velocity.velocities, velocity.covariances)
        state = motion_state.next_state(store.state[rows], median, cfg)
        store.state[rows] = state
        ahead, ahead_cov, _, steps_cov = self.predictor(x, P)
        # the reported path moves at the posterior's mean velocity, the corridor's steps at that of the
        # posterior under the filter's Gaussian alone (their spreads are the filter's): the heavy tail
        # shortens a few fast walkers' steps, and the synthetic scenes' conflict recall fell 88.4 -> 87.6 %
        # (seeds 0-3) with it; on the KITTI drives the corridor at the filter's velocity flagged 14 pairs
        # (moving) and 3 (parked), at the Gaussian posterior's 8 and 3 (docs/behaviour.md)
        ahead = self.predictor.reported(np.column_stack([x[:, 0], mean[:, 0], x[:, 2], mean[:, 1]]))
        moved = np.column_stack([x[:, 0], corridor[:, 0], x[:, 2], corridor[:, 1]])
        fast = np.hypot(corridor[:, 0], corridor[:, 1])
        if fast.max() > MAX_PEDESTRIAN_SPEED_MPS:  # the corridor's positions at most that fast
            moved[:, 1::2] *= np.minimum(MAX_PEDESTRIAN_SPEED_MPS / np.maximum(fast, 1e-9), 1.0)[:, None]
        steps = self.predictor.steps(moved)
        conflict = conflict_of(path, steps, steps_cov, cfg.corridor_half_width_m, cfg.corridor_front_m)
        return Behaviour(held[0], held[1], store.available[rows], held[2], held[3], state, speed, speed_std,
                         self.horizons, ahead, ahead_cov, conflict.probability, conflict.time_s, conflict.time_std_s,
                         conflict.closest_m, conflict.closest_std_m, conflict.closest_time_s,
                         float(self.conflict_times[-1]), path.motion.speed, path.motion.yaw_rate, path.xy)

    def _orient(self, frame: Frame, peds: Pedestrians, rows: np.ndarray, velocity: VelocityStats) -> None:
        """Predict the heading grids of the store's ``rows`` (N,) to the frame's time, update them with
        the skeleton cue and the walking direction (``velocity``, N) and keep what they say
        (``TrackStore.held``, ``TrackStore.available``)."""
        t, store, g = frame.timestamp, self.store, self.grid
        walk, available_std, half = self.angles
        # every row of the store (the live tracks absent from this frame too) is predicted to now, so that
        # all share one time and the next prediction is one matrix product (a wrapped normal's spread
        # over two gaps in turn is that over their sum)
        store.p = heading_filter.spread(store.p, t - store.time, walk, g)
        store.time[:] = t
        p = store.p[rows]
        cam_to_world = frame.cam_to_world
        rays = keypoint_rays(peds.keypoints[:, CUE_KEYPOINTS], self._inverse_intrinsics(frame), cam_to_world)
        cue = cue_from_rays(rays, peds.confidences, peds.positions, cam_to_world[:3, 3],
                            float(frame.camera.intrinsics[0, 0]))
        cos_a = cue.toward @ g.cos_sin
        moving, _ = walking_likelihood(velocity, g.cos_sin)
        p = heading_filter.update(p, cue_likelihood(cue, cos_a, cue.right @ g.cos_sin) * moving)
        store.p[rows] = p
        yaw, yaw_std, available = heading_filter.summary(p, available_std)
        store.held[:, rows] = (yaw, yaw_std, facing.body_facing_from(p, cos_a, math.cos(half)),
                               facing.head_facing(cue, half))
        store.available[rows] = available


#: How fast an unobserved heading spreads (degrees per square root of a second; a random walk): a
#: gap of a few seconds leaves it unavailable. Set on the built-in scenes, not tuned.
HEADING_RANDOM_WALK_DEG = 45.0
#: Time step (s) of the corridor's prediction: a pedestrian at 1.4 m/s moves 0.14 m per step, well
#: inside the corridor's 1.5 m half width.
CONFLICT_STEP_S = 0.1
#: The corridor's prediction takes a velocity (the posterior's mean) faster than this (m/s) at this
#: speed, in its direction: a track whose range jumps can show 5-10 m/s, and people rarely run faster.
#: Set for people, not tuned (3 and 6 m/s moved the conflict precision by under 1 point,
#: docs/behaviour.md); the reported path is not changed.
MAX_PEDESTRIAN_SPEED_MPS = 4.0

#: Timestamps this close (s) to ``orientation_interval_s`` after the last orientation count as that far
#: (frame times are not exact multiples of the frame period).
REFRESH_TOLERANCE_S = 1e-3

#: A filter state (m, m/s) or covariance entry (m^2, ...) beyond these is not used (an overflowed track).
STATE_LIMIT = (1e6, 1e8)


def _usable_states(peds: Pedestrians, x: np.ndarray, P: np.ndarray, started: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """x (N, 4), P (N, 4, 4) with the rows not started, not finite or beyond :data:`STATE_LIMIT`
    replaced by the reported position, standing, with a 2 m/s velocity spread."""
    usable = (started & (np.abs(x) < STATE_LIMIT[0]).all(axis=1)
              & (np.abs(P) < STATE_LIMIT[1]).reshape(len(P), 16).all(axis=1))  # False for NaN, inf
    x, P, fresh = x.copy(), P.copy(), ~usable
    x[fresh] = np.column_stack([peds.positions[fresh, 0], np.zeros(fresh.sum()), peds.positions[fresh, 1],
                                np.zeros(fresh.sum())])
    prior = np.repeat(np.diag([1.0, 4.0, 1.0, 4.0])[None], fresh.sum(), axis=0)
    cov = _finite_cov4(peds.covariances[fresh])
    prior[:, 0, 0], prior[:, 0, 2], prior[:, 2, 0], prior[:, 2, 2] = (cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 0],
                                                                      cov[:, 1, 1])
    P[fresh] = prior
    return x, P


def _finite_cov4(cov: np.ndarray) -> np.ndarray:
    """Position covariances (N, 2, 2) with non-finite or absurd ones replaced by 100 m^2 each way."""
    good = (np.abs(cov) < STATE_LIMIT[1]).reshape(len(cov), 4).all(axis=1)
    return np.where(good[:, None, None], cov, 100.0 * np.eye(2))
