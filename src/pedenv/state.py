"""The environment model at one point in time: what ``model.update(frame)`` returns."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.records import EgoPose
from pedenv.skeleton import KEYPOINT_NAMES


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
        }
