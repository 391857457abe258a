"""The one stateful piece: :class:`VisualOdometry` takes a recording's frames in order and gives its ego poses."""

from __future__ import annotations

import dataclasses

import cv2
import numpy as np

from pedenv.errors import InputError, check_array
from pedenv.geometry import invert_transform, rotation_to_quaternion
from pedenv.odometry.motion import Step, estimate_step, fill_lengths, pooled_pitch, road_length
from pedenv.recordings.ego_poses import EgoTrajectory

#: The ``source`` of an estimated trajectory (what its InputErrors and ``run.json`` name).
ESTIMATED_SOURCE = "ego_poses_estimated.csv"
#: Steps whose road pitches are pooled (their median) before each is refitted with it and its road
#: tracks are let go: 100 steps (10 s at 10 Hz) follow a slow change of the car's load while
#: keeping at most 100 steps' tracks in memory on a long video.
PITCH_POOL_STEPS = 100


class VisualOdometry:
    """Ego poses of a moving camera from its images (:mod:`pedenv.odometry`).

    intrinsics: (3, 3) pixels. cam_to_vehicle: (4, 4) camera (optical) -> vehicle (x forward,
    y left, z up, origin on the road); its height ``cam_to_vehicle[2, 3]`` over the road, metres,
    gives the motion its scale and must be positive. The world of the poses is the vehicle frame
    of the first frame.
    """

    def __init__(self, intrinsics: np.ndarray, cam_to_vehicle: np.ndarray) -> None:
        self.intrinsics = check_array("intrinsics", intrinsics, (3, 3))
        self.cam_to_vehicle = check_array("cam_to_vehicle", cam_to_vehicle, (4, 4))
        if not self.cam_to_vehicle[2, 3] > 0:
            raise InputError(f"cam_to_vehicle: the camera must be above the road (z > 0 m), "
                             f"got {self.cam_to_vehicle[2, 3]:g} m")
        self.timestamps: list[float] = []
        self.key_timestamps: list[float] = []
        self.steps: list[Step] = []
        self._settled = 0  # the steps before this one have their final length and no road tracks
        self._key: np.ndarray | None = None
        self._boxes: np.ndarray | None = None
        self._where = "frame"

    def update(self, image: np.ndarray, timestamp: float, boxes: np.ndarray | None = None,
               where: str = "frame") -> None:
        """Add the next frame: ``image`` (H, W) grey or (H, W, 3) RGB uint8 at ``timestamp`` seconds
        (after the previous one); ``boxes`` (N, 4) ``[x1, y1, x2, y2]`` pixels: its people (left out).

        The frame is compared with the last keyframe; when the image changed measurably (a
        :class:`~pedenv.odometry.motion.Step` ``seen``) the step is kept and the frame becomes the
        keyframe, else the keyframe stays (a static camera does not drift; a slow car's motion adds up
        until it shows). ``where`` names the frame in errors (InputError: too dark or blurred to track,
        timestamps out of order)."""
        gray = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image
        if self.timestamps and not timestamp > self.timestamps[-1]:
            raise InputError(f"{where}: timestamp {timestamp:.6f} s is not after the previous frame's "
                             f"{self.timestamps[-1]:.6f} s")
        self.timestamps.append(float(timestamp))
        if self._key is not None:
            step = estimate_step(self._key, gray, self.intrinsics, self.cam_to_vehicle, boxes=self._boxes,
                                 where=self._where)
            if not step.seen:
                return
            self.steps.append(step)
            if len(self.steps) - self._settled >= PITCH_POOL_STEPS:
                self._settle()
        self._key, self._boxes, self._where = gray, boxes, where
        self.key_timestamps.append(float(timestamp))

    def poses(self, where: str = "the recording") -> np.ndarray:
        """(K, 4, 4) vehicle -> world transforms, one per keyframe (at :attr:`key_timestamps`; the first
        the identity); steps whose road was not seen get their neighbours' speed
        (:func:`~pedenv.odometry.motion.fill_lengths`)."""
        if not self.timestamps:
            raise InputError(f"{where}: no frames for visual odometry")
        lengths = fill_lengths(self.lengths(), np.diff(self.key_timestamps), where)
        return chain_poses([s.rotation for s in self.steps],
                           [s.direction * n for s, n in zip(self.steps, lengths)], self.cam_to_vehicle)

    def lengths(self) -> np.ndarray:
        """(S,) metres: each step's length refitted with the road's pitch fixed at the median of the
        steps' own fits over its pool of :data:`PITCH_POOL_STEPS` (the camera's pitch over the road:
        one step's pitch and length trade off against each other); NaN where the road was not seen."""
        self._settle()
        return np.array([s.length for s in self.steps])

    def _settle(self) -> None:
        """Give the steps not yet settled their pooled pitch's length and let their road tracks go."""
        pool = self.steps[self._settled:]
        pitch = pooled_pitch(pool)
        self.steps[self._settled:] = [
            dataclasses.replace(s, length=road_length(s, self.intrinsics, self.cam_to_vehicle, pitch),
                                road=(np.empty((0, 2)), np.empty((0, 2)))) for s in pool]
        self._settled = len(self.steps)

    def trajectory(self, where: str = "the recording") -> EgoTrajectory:
        """The poses as an :class:`~pedenv.recordings.ego_poses.EgoTrajectory` (``source`` :data:`ESTIMATED_SOURCE`):
        the keyframes' poses, and the last frame's (the last keyframe's: the image has not changed
        measurably since) when it is no keyframe; frames between keyframes are interpolated."""
        poses = self.poses(where)
        stamps = list(self.key_timestamps)
        if self.timestamps[-1] > stamps[-1]:
            poses, stamps = np.concatenate([poses, poses[-1:]]), [*stamps, self.timestamps[-1]]
        quats = np.array([rotation_to_quaternion(p[:3, :3]) for p in poses])
        return EgoTrajectory(np.array(stamps), poses[:, :3, 3].copy(), quats, ESTIMATED_SOURCE)


def chain_poses(rotations: list[np.ndarray], translations: list[np.ndarray], cam_to_vehicle: np.ndarray) -> np.ndarray:
    """(S + 1, 4, 4) vehicle -> world poses from S camera steps (``x1 = rotation @ x0 + translation``,
    camera frame, metres), the world being the first vehicle frame."""
    to_vehicle = np.asarray(cam_to_vehicle, dtype=np.float64)
    to_camera = invert_transform(to_vehicle)
    poses = [np.eye(4)]
    for rotation, translation in zip(rotations, translations):
        back = np.eye(4)  # camera 1 -> camera 0
        back[:3, :3] = rotation.T
        back[:3, 3] = -rotation.T @ translation
        poses.append(poses[-1] @ to_vehicle @ back @ to_camera)
    return np.array(poses)
