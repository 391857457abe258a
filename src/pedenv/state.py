"""The environment model at one point in time: what ``model.update(frame)`` returns."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pedenv.records import EgoPose
from pedenv.skeleton import KEYPOINT_NAMES


@dataclass(frozen=True)
class Behaviour:
    """What the N pedestrians of one frame are about to do (``Config.behaviour``, :mod:`pedenv.behaviour`).

    Per pedestrian (row i as in :class:`Pedestrians`):
    yaw: (N,) radians, world frame, counter-clockwise from +x: the direction the body faces.
    yaw_std: (N,) radians, the spread about it (1.81 when nothing is known).
    orientation_availability: (N,) int8, 0 unavailable, 1 sign unknown (yaw or yaw + pi),
        2 available (``pedenv.behaviour.heading_filter.AVAILABILITY_NAMES``).
    facing_probability: (N,) probability that the body faces the ego camera.
    head_facing_probability: (N,) the same for the head, from this frame's face keypoints.
    motion_state: (N,) int8, 0 standing, 1 walking, 2 running. speed, speed_std: (N,) m/s.
    predicted_positions: (N, H, 2) world x-y, metres, at ``horizons`` (H,) seconds ahead;
        predicted_covariances: (N, H, 2, 2) m^2.
    conflict_probability: (N,) probability of entering the corridor around the ego's path
        within ``conflict_horizon`` s; conflict_time, conflict_time_std: (N,) s until then
        (the horizon where it does not); closest_approach, closest_approach_std: (N,) metres
        between pedestrian and ego at the same time; closest_approach_time: (N,) s ahead.
    Per frame: ego_speed (m/s, negative reversing), ego_yaw_rate (rad/s), ego_path (K, 2)
    world x-y metres, the ego's predicted path up to ``conflict_horizon`` s.
    """

    yaw: np.ndarray
    yaw_std: np.ndarray
    orientation_availability: np.ndarray
    facing_probability: np.ndarray
    head_facing_probability: np.ndarray
    motion_state: np.ndarray
    speed: np.ndarray
    speed_std: np.ndarray
    horizons: np.ndarray
    predicted_positions: np.ndarray
    predicted_covariances: np.ndarray
    conflict_probability: np.ndarray
    conflict_time: np.ndarray
    conflict_time_std: np.ndarray
    closest_approach: np.ndarray
    closest_approach_std: np.ndarray
    closest_approach_time: np.ndarray
    conflict_horizon: float = 0.0
    ego_speed: float = 0.0
    ego_yaw_rate: float = 0.0
    ego_path: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def __len__(self) -> int:
        return len(self.yaw)

    @classmethod
    def empty(cls, horizons: np.ndarray) -> Behaviour:
        z, h = np.zeros(0), len(horizons)
        i8 = np.zeros(0, np.int8)
        return cls(z, z, i8, z, z, i8, z, z, np.asarray(horizons, float), np.zeros((0, h, 2)),
                   np.zeros((0, h, 2, 2)), z, z, z, z, z, z)

    def row(self, i: int, decimals: int) -> dict:
        """The JSON-ready fields of pedestrian ``i`` (see :meth:`EnvironmentState.to_dict`)."""
        r = lambda a: np.round(a, decimals).tolist()  # noqa: E731
        f = lambda a: round(float(a[i]), decimals)  # noqa: E731
        return {
            "yaw": f(self.yaw), "yaw_std": f(self.yaw_std),
            "orientation_availability": AVAILABILITY[int(self.orientation_availability[i])],
            "facing_probability": f(self.facing_probability),
            "head_facing_probability": f(self.head_facing_probability),
            "motion_state": MOTION_STATES[int(self.motion_state[i])], "speed": f(self.speed),
            "speed_std": f(self.speed_std), "predicted_positions": r(self.predicted_positions[i]),
            "predicted_covariances": r(self.predicted_covariances[i]),
            "conflict": {"probability": f(self.conflict_probability), "time": f(self.conflict_time),
                         "time_std": f(self.conflict_time_std), "closest_approach": f(self.closest_approach),
                         "closest_approach_std": f(self.closest_approach_std),
                         "closest_approach_time": f(self.closest_approach_time)},
        }


#: Names of ``Behaviour.orientation_availability`` and ``Behaviour.motion_state`` codes.
AVAILABILITY = ("unavailable", "sign_unknown", "available")
MOTION_STATES = ("standing", "walking", "running")


@dataclass(frozen=True)
class Pedestrians:
    """The N pedestrians seen in one frame, as arrays (row i is one pedestrian).

    track_ids: (N,) int64. ages: (N,) int64, frames the track has been seen.
    positions: (N, 3) world frame, metres, the ground point under the person.
    velocities: (N, 3) world frame, m/s (z is 0: the filter runs on the ground plane).
    covariances: (N, 2, 2) m^2, the x-y position covariance of the filter.
    keypoints: (N, 17, 2) pixels; confidences: (N, 17); boxes: (N, 4) pixels.
    keypoints_3d: (N, 17, 3) world frame, metres, the skeleton in 3D.
    distances: (N,) metres from the camera to the person.
    sources: (N,) str, how the position was found (see ``pedenv.localization.paper``).
    behaviour: what they are about to do (:class:`Behaviour`), or None where
        ``Config.behaviour`` is off (``--method paper``).
    """

    track_ids: np.ndarray
    ages: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    covariances: np.ndarray
    keypoints: np.ndarray
    confidences: np.ndarray
    boxes: np.ndarray
    keypoints_3d: np.ndarray
    distances: np.ndarray
    sources: np.ndarray
    behaviour: Behaviour | None = None

    def __len__(self) -> int:
        return len(self.track_ids)

    @classmethod
    def empty(cls) -> Pedestrians:
        z = np.zeros
        return cls(z(0, np.int64), z(0, np.int64), z((0, 3)), z((0, 3)), z((0, 2, 2)), z((0, 17, 2)),
                   z((0, 17)), z((0, 4)), z((0, 17, 3)), z(0), np.zeros(0, dtype="<U32"))


@dataclass(frozen=True)
class EnvironmentState:
    """Everything known about the pedestrians at ``timestamp`` (seconds)."""

    frame_index: int
    timestamp: float
    ego: EgoPose
    pedestrians: Pedestrians
    scene: str = ""

    def to_dict(self, decimals: int = 3) -> dict:
        """JSON-ready dict: one line of the JSON Lines environment model."""
        p = self.pedestrians
        r = lambda a: np.round(a, decimals).tolist()  # noqa: E731
        peds = [
            {
                "track_id": int(p.track_ids[i]),
                "age": int(p.ages[i]),
                "position": r(p.positions[i]),
                "velocity": r(p.velocities[i]),
                "covariance_xy": r(p.covariances[i]),
                "distance": round(float(p.distances[i]), decimals),
                "source": str(p.sources[i]),
                "box": r(p.boxes[i]),
                "skeleton": {
                    "uv": r(p.keypoints[i]),
                    "confidence": r(p.confidences[i]),
                    "xyz": r(p.keypoints_3d[i]),
                },
                **({"behaviour": p.behaviour.row(i, decimals)} if p.behaviour is not None else {}),
            }
            for i in range(len(p))
        ]
        return {
            "scene": self.scene,
            "frame": self.frame_index,
            "timestamp": round(self.timestamp, 6),
            "ego": {
                "translation": r(self.ego.translation),
                "rotation": r(self.ego.rotation),
                "yaw": round(self.ego.yaw, 6),
            },
            "keypoint_names": list(KEYPOINT_NAMES),
            "pedestrians": peds,
            **({"ego_motion": {"speed": round(p.behaviour.ego_speed, decimals),
                               "yaw_rate": round(p.behaviour.ego_yaw_rate, decimals),
                               "horizons": r(p.behaviour.horizons), "path": r(p.behaviour.ego_path)}}
               if p.behaviour is not None else {}),
        }
