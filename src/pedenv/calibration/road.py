"""The road cue of a vehicle camera: the car moves along the road, so its direction of travel is level.

Between two frames of a moving car, visual odometry (:mod:`pedenv.odometry`: the essential matrix
of the corners tracked from one frame to the next) gives the camera's rotation and the direction of
its translation in the camera's own axes. The car rolls on the road: that direction lies in the road
plane, so its vanishing point (the focus of expansion) lies on the horizon. Pooled over many steps it
fixes the camera's pitch against the road (and its yaw on the car, which pedenv does not need).

The road's height under the camera is seen only where the steps' metric lengths are known (ego poses
given with the images): the odometry measures each step in units of the camera's height over the
road it sees (the road plane's homography, :func:`pedenv.odometry.ground.fit_road`, with a nominal
camera :data:`NOMINAL_MOUNTING`), so a step of known length gives the height in metres
(:class:`RoadScale`, :func:`road_scale`): the odometry's road-plane scale turned round.

Frames: the camera frame is optical (x right, y down, z forward); a *travel direction* is the unit
vector from the camera's centre at one keyframe to the next, in the first keyframe's camera axes.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pedenv.calibration.geometry import camera_rotation
from pedenv.errors import InputError, check_array
from pedenv.records import default_cam_to_vehicle

if TYPE_CHECKING:
    from pedenv.odometry.estimator import VisualOdometry
    from pedenv.recordings.ego_poses import EgoTrajectory

#: 1-sigma of one step's travel elevation, degrees, used while too few steps give their own scatter:
#: the monocular essential matrix's direction against GPS/IMU on KITTI raw 2011_09_26_drive_0002
#: (9 steps at 9 m/s, 0.36 deg RMS, rounded up), which holds the car's own pitching on the road's bumps.
STEP_ELEVATION_STD_DEG = 0.4
#: Steps from which their own scatter replaces :data:`STEP_ELEVATION_STD_DEG`.
MIN_STEPS_FOR_SCATTER = 10
#: 1-sigma of the pooled direction of travel against the ground the people stand on, degrees: the
#: RMS difference (0.21 deg) between ORB-SLAM3's mean travel direction and the plane of the labelled
#: boxes' bottoms over six moving KITTI tracking drives (0000, 0001, 0004, 0011, 0013, 0015): the
#: road's vertical curve, the car's load, the labelled ground's own slope. It bounds the cue however
#: many steps pass.
TRAVEL_GROUND_STD_DEG = 0.2
#: Steps whose elevation lies further than this many robust sigmas (1.4826 MAD) from the median are
#: left out (a turn's chord cut short by a bad essential matrix, a mover taken for the world), once
#: at least :data:`MIN_STEPS_FOR_SCATTER` steps give a median to judge them by.
OUTLIER_SIGMA = 3.0
#: Where the odometry looks for the road while it only serves the direction: a level camera 1.5 m
#: up (the road patch takes extra corners there; the direction and rotation do not depend on it).
NOMINAL_MOUNTING = default_cam_to_vehicle(1.5)
#: 1-sigma of one step's camera height from the road's scale, share of it, used while fewer than
#: :data:`MIN_STEPS_FOR_SCATTER` steps give their own scatter: the nominal camera's road-plane step
#: lengths against GPS/IMU's on KITTI raw 2011_09_26_drive_0002 (9 steps at 9 m/s: 3.2 %, rounded up).
STEP_SCALE_STD = 0.035
#: 1-sigma of the pooled road-scale height against the ground the people stand on, share of it,
#: however many steps pass: the same drive's 9 steps pooled put the camera 1.61 m up against KITTI's
#: 1.65 m (-2.5 %, rounded up: the road patch's camber and the car's load stay in every step).
ROAD_SCALE_STD = 0.03
#: Shortest step, metres of the ego poses, that scales the road: a shorter one's length is mostly its
#: poses' noise (the odometry's own parallax gate keeps shorter steps only for their direction).
MIN_SCALE_STEP_M = 0.3


@dataclass(frozen=True)
class RoadCue:
    """The pooled direction of travel of a moving vehicle camera.

    direction: (3,) unit vector, camera axes (optical): the mean travel direction, its focus of
    expansion on the horizon. std: 1-sigma of its elevation against the road, radians (the steps'
    scatter over their count, and :data:`TRAVEL_GROUND_STD_DEG`). steps: moving steps pooled;
    dropped: steps left out as outliers; scatter: 1-sigma of one step's elevation used, radians.
    """

    direction: np.ndarray
    std: float
    steps: int
    dropped: int = 0
    scatter: float = float(np.radians(STEP_ELEVATION_STD_DEG))

    def __post_init__(self) -> None:
        check_array("direction", self.direction, (3,))

    @property
    def pitch(self) -> float:
        """The camera's pitch against the road the cue alone gives, radians (> 0 looks down), roll 0."""
        d = self.direction
        return float(np.arctan2(-d[1], np.hypot(d[0], d[2])))

    def misfit(self, tilt: float, roll: float) -> float:
        """The travel direction's elevation above the road for a camera of ``tilt`` and ``roll``
        (radians, :func:`pedenv.calibration.geometry.camera_rotation`): zero where the camera agrees."""
        world = camera_rotation(tilt, roll) @ self.direction
        return float(np.arcsin(np.clip(world[2], -1.0, 1.0)))

    def summary(self) -> dict:
        """JSON-ready: the pitch the road alone gives, its 1-sigma (degrees), the steps."""
        d = self.direction
        return {"pitch_deg": float(np.degrees(self.pitch)), "pitch_std_deg": float(np.degrees(self.std)),
                "yaw_deg": float(np.degrees(np.arctan2(d[0], d[2]))), "steps": self.steps, "dropped": self.dropped}


@dataclass(frozen=True)
class RoadScale:
    """The camera's height over the road from the road's image motion and the ego poses' step lengths.

    height: metres; std: its 1-sigma, metres (the steps' scatter over their count, and
    :data:`ROAD_SCALE_STD`); steps: steps pooled; dropped: steps left out as outliers; scatter:
    1-sigma of one step's height used, share of it.
    """

    height: float
    std: float
    steps: int
    dropped: int = 0
    scatter: float = STEP_SCALE_STD

    def summary(self) -> dict:
        """JSON-ready: the height the road's scale gives, its 1-sigma (metres), the steps."""
        return {"height_m": self.height, "height_std_m": self.std, "steps": self.steps, "dropped": self.dropped}


def road_scale(odometry: np.ndarray, ego: np.ndarray,
               nominal: float = float(NOMINAL_MOUNTING[2, 3])) -> RoadScale | None:
    """The :class:`RoadScale` of steps whose lengths the odometry measured ``odometry`` (N,) metres with a
    camera ``nominal`` metres over the road and the ego poses give ``ego`` (N,) metres; None without a
    step that both measured (finite, ego at least :data:`MIN_SCALE_STEP_M`). Each step's height is
    ``nominal * ego / odometry``; outliers (:data:`OUTLIER_SIGMA` robust sigmas of its log, from
    :data:`MIN_STEPS_FOR_SCATTER` steps) are left out, the rest pooled as the lengths' ratio."""
    odo, ref = np.asarray(odometry, float).ravel(), np.asarray(ego, float).ravel()
    with np.errstate(invalid="ignore"):
        usable = np.isfinite(odo) & np.isfinite(ref) & (odo > 0) & (ref >= MIN_SCALE_STEP_M)
    odo, ref = odo[usable], ref[usable]
    if not len(odo):
        return None
    logs = np.log(nominal * ref / odo)
    keep = np.ones(len(odo), bool)
    if len(odo) >= MIN_STEPS_FOR_SCATTER:
        mad = 1.4826 * float(np.median(np.abs(logs - np.median(logs))))
        keep = np.abs(logs - np.median(logs)) <= OUTLIER_SIGMA * max(mad, 1e-4)
    n = int(keep.sum())
    height = nominal * float(ref[keep].sum() / odo[keep].sum())
    scatter = float(np.std(logs[keep], ddof=1)) if n >= MIN_STEPS_FOR_SCATTER else STEP_SCALE_STD
    return RoadScale(height, height * float(np.hypot(scatter / np.sqrt(n), ROAD_SCALE_STD)), n, len(odo) - n, scatter)


def ego_length(trajectory: EgoTrajectory, timestamps: np.ndarray) -> Callable[[int, int], float]:
    """The metres the car moved between two frames (their indices into ``timestamps`` (N,) seconds) by
    ``trajectory``, its poses interpolated (the chord, as the odometry's step is); NaN outside it."""
    stamps = np.asarray(timestamps, float)

    def length(first: int, last: int) -> float:
        if not 0 <= first < len(stamps) or not 0 <= last < len(stamps):
            return float("nan")
        a, b = trajectory.at(float(stamps[first])), trajectory.at(float(stamps[last]))
        return float("nan") if a is None or b is None else float(np.linalg.norm(b.translation - a.translation))

    return length


def travel_direction(rotation: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """(3,) unit travel direction in the first camera's axes of a step ``x1 = rotation @ x0 + t``,
    ``t`` along ``direction`` (3,) (:class:`pedenv.odometry.motion.Step`), signed to point forward."""
    centre = -np.asarray(rotation, float).T @ np.asarray(direction, float)  # camera 1's centre in camera 0
    centre = centre / np.linalg.norm(centre)
    return centre if centre[2] >= 0 else -centre


def elevations(directions: np.ndarray) -> np.ndarray:
    """(N,) radians: each travel direction's (N, 3) angle above the camera's x-z plane."""
    d = np.asarray(directions, float).reshape(-1, 3)
    return np.arctan2(-d[:, 1], np.hypot(d[:, 0], d[:, 2]))


def road_cue(directions: np.ndarray) -> RoadCue | None:
    """The :class:`RoadCue` of travel directions (N, 3) (camera axes, one per moving step), or None
    without any. Outliers are left out (:data:`OUTLIER_SIGMA`), the rest averaged as unit vectors."""
    d = np.asarray(directions, float).reshape(-1, 3)
    if len(d) == 0:
        return None
    e = elevations(d)
    keep = np.ones(len(d), bool)
    if len(d) >= MIN_STEPS_FOR_SCATTER:
        mad = 1.4826 * float(np.median(np.abs(e - np.median(e))))
        keep = np.abs(e - np.median(e)) <= OUTLIER_SIGMA * max(mad, 1e-4)
    mean = d[keep].mean(axis=0)
    n = int(keep.sum())
    scatter = float(np.std(e[keep], ddof=1)) if n >= MIN_STEPS_FOR_SCATTER else np.radians(STEP_ELEVATION_STD_DEG)
    std = float(np.hypot(scatter / np.sqrt(n), np.radians(TRAVEL_GROUND_STD_DEG)))
    return RoadCue(mean / np.linalg.norm(mean), std, n, int(len(d) - n), scatter)


class TravelWatcher:
    """The travel directions of a recording's frames, taken in passing (:meth:`watch`).

    intrinsics: (3, 3) pixels. Each frame goes to a :class:`pedenv.odometry.VisualOdometry` (its
    keyframes wait for measurable motion; a parked car gives no step). A frame the odometry
    refuses (too dark, blurred or covered) ends its run of steps; the next frame starts another.
    ego_length: where the ego poses are given, the metres the car moved between two frames (their
    indices): the road's scale then gives the camera's height (:meth:`scale`).
    """

    def __init__(self, intrinsics: np.ndarray, ego_length: Callable[[int, int], float] | None = None) -> None:
        self.intrinsics = check_array("intrinsics", intrinsics, (3, 3))
        self.ego_length = ego_length
        self._odometry: VisualOdometry | None = None
        self._directions: list[np.ndarray] = []
        self._taken = 0  # the current odometry's steps already in ``_directions``
        self._spans: list[tuple[float, float, float]] = []  # ended runs' moving steps: first, last frame, length
        self.refused = 0

    def add(self, index: int, image: np.ndarray) -> None:
        """Frame ``index`` (its time in frames), ``image`` (H, W, 3) RGB or (H, W) grey uint8."""
        from pedenv.odometry.estimator import VisualOdometry

        if self._odometry is None:
            self._odometry = VisualOdometry(self.intrinsics, NOMINAL_MOUNTING)
        try:
            self._odometry.update(image, float(index), where=f"frame {index}")
        except InputError:
            self.refused += 1
            self._collect()
            self._spans += self._current_spans()
            self._odometry, self._taken = None, 0

    def watch(self, frames: Iterable[tuple[int, np.ndarray]]) -> Iterator[tuple[int, np.ndarray]]:
        """``frames`` ((index, image) pairs) passed on unchanged, each added on the way (:meth:`add`)."""
        for index, image in frames:
            self.add(index, image)
            yield index, image

    def _collect(self) -> None:
        if self._odometry is not None:
            fresh = self._odometry.steps[self._taken:]
            self._directions += [travel_direction(s.rotation, s.direction) for s in fresh if s.moved]
            self._taken += len(fresh)

    def directions(self) -> np.ndarray:
        """(N, 3) the travel directions of the moving steps seen so far."""
        self._collect()
        return np.array(self._directions).reshape(-1, 3)

    def cue(self) -> RoadCue | None:
        """The pooled :class:`RoadCue` of the steps seen so far, or None (a parked car, no motion)."""
        return road_cue(self.directions())

    def _current_spans(self) -> list[tuple[float, float, float]]:
        if self._odometry is None:
            return []
        odometry, lengths = self._odometry, self._odometry.lengths()
        keys = odometry.key_timestamps
        return [(keys[i], keys[i + 1], float(n)) for i, (s, n) in enumerate(zip(odometry.steps, lengths)) if s.moved]

    def scale(self) -> RoadScale | None:
        """The :class:`RoadScale` of the moving steps seen so far against ``ego_length``, or None (no ego
        poses, no moving step)."""
        if self.ego_length is None:
            return None
        spans = self._spans + self._current_spans()
        ego = np.array([self.ego_length(int(a), int(b)) for a, b, _ in spans])
        return road_scale(np.array([n for _, _, n in spans]), ego)
