"""Visual odometry as a stage of ``pedenv run``'s frame loop: frames in, each frame's final ego pose out.

:class:`OdometryStream` takes the frames in order as they are decoded (the reader's thread, beside
the network) and hands back each frame's pose once it is final, :data:`POSE_LAG_FRAMES` frames
later: a pose is never changed after it was handed on (the tracker and every output have used it).
It is causal: a step's length comes from its own road tracks refitted with the road's pitch pooled
(the median) over the :data:`~pedenv.odometry.estimator.PITCH_POOL_STEPS` steps up to it and the
few steps after it that the lag has seen; a step whose road gave no length takes the speed of the
measured steps around it that are known by then. The steps themselves are
:func:`~pedenv.odometry.motion.estimate_step`'s, as :class:`~pedenv.odometry.estimator.VisualOdometry`
(the whole recording at once: ``pedenv calibrate --odometry``) takes them.
"""

from __future__ import annotations

import dataclasses
import time
from typing import Any

import cv2
import numpy as np

from pedenv.errors import InputError, check_array
from pedenv.geometry import rotation_to_quaternion
from pedenv.odometry.estimator import ESTIMATED_SOURCE, PITCH_POOL_STEPS, chain_poses
from pedenv.odometry.motion import Step, estimate_step, fill_lengths, pooled_pitch, road_length
from pedenv.recordings.ego_poses import EgoTrajectory

#: Frames a pose lags behind the newest frame estimated: the steps of these frames join the pitch's pool
#: and the neighbours' speed of a step without road scale. The frames wait, decoded, between the reader
#: and the network (4 at 1600x900: 17 MB). On KITTI raw 0002's 10 frames against the GPS distance: no lag
#: +2.84 %, 2 frames +1.53 %, 4 +1.94 %, all 9 steps (the whole drive's estimate) +1.69 %, the yaw the same;
#: the poses at most 11.5, 2.9 and 2.8 cm from the whole drive's. A frame lagging is a frame later out of the
#: run (``--realtime``: 0.4 s at 10 Hz).
POSE_LAG_FRAMES = 4
#: Most frames that wait for their poses before any step was measured by the road (the first step
#: with a length gives the speed of those before it): 30 frames, 3 s at 10 Hz; a recording whose first
#: 30 frames move without road is refused (InputError), never run with made-up poses.
MAX_WAIT_FRAMES = 30


class OdometryStream:
    """Ego poses (vehicle -> world, (4, 4)) of a moving camera's frames, each final once handed on (module doc).

    intrinsics: (3, 3) pixels. cam_to_vehicle: (4, 4) camera -> vehicle, the camera above the road.
    lag: :data:`POSE_LAG_FRAMES`. The world is the vehicle frame of the first frame.
    """

    def __init__(self, intrinsics: np.ndarray, cam_to_vehicle: np.ndarray, lag: int = POSE_LAG_FRAMES) -> None:
        self.intrinsics = check_array("intrinsics", intrinsics, (3, 3))
        self.cam_to_vehicle = check_array("cam_to_vehicle", cam_to_vehicle, (4, 4))
        if not self.cam_to_vehicle[2, 3] > 0:
            raise InputError(f"cam_to_vehicle: the camera must be above the road (z > 0 m), "
                             f"got {self.cam_to_vehicle[2, 3]:g} m")
        self.lag = lag
        self.timestamps: list[float] = []  # every frame added
        self.key_frames: list[int] = []  # the frame of each keyframe; step s ends at keyframe s + 1
        self.steps: list[Step] = []
        self.lengths: list[float] = []  # the final lengths of the first steps, metres
        self.filled: list[bool] = []  # whether each final length is the neighbours' speed
        self.key_poses: list[np.ndarray] = []  # the final poses of the first keyframes
        self.poses: list[np.ndarray] = []  # the frames' poses handed on
        self.spent = [0.0, 0.0]  # wall and CPU (this thread) seconds in :meth:`add`
        self._key: np.ndarray | None = None
        self._where = "frame"

    def add(self, image: np.ndarray, timestamp: float, where: str = "frame") -> list[np.ndarray]:
        """Add the next frame, ``image`` (H, W) grey or (H, W, 3) RGB uint8 at ``timestamp`` seconds; returns
        the poses of the next frames not yet handed on that are final now, in order. InputError: too dark or
        blurred to track (``where`` names the frame), timestamps out of order, no road in
        :data:`MAX_WAIT_FRAMES` frames."""
        start = time.perf_counter(), time.thread_time()
        if self.timestamps and not timestamp > self.timestamps[-1]:
            raise InputError(f"{where}: timestamp {timestamp:.6f} s is not after the previous frame's "
                             f"{self.timestamps[-1]:.6f} s")
        gray = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) if image.ndim == 3 else image
        self.timestamps.append(float(timestamp))
        step = None if self._key is None else estimate_step(self._key, gray, self.intrinsics, self.cam_to_vehicle,
                                                            where=self._where)
        if step is None or step.seen:
            if step is not None:
                self.steps.append(step)
            self._key, self._where = gray, where
            self.key_frames.append(len(self.timestamps) - 1)
        ready = self._release(len(self.timestamps) - 1 - self.lag, where)
        if len(self.timestamps) - len(self.poses) > self.lag + MAX_WAIT_FRAMES:
            raise InputError(f"{where}: visual odometry saw no road ahead of the camera in "
                             f"{len(self.timestamps)} frames to give the motion its scale (check the calibration's "
                             "cam_to_vehicle: the camera's height and pitch); give --ego-poses")
        self.spent = [self.spent[0] + time.perf_counter() - start[0], self.spent[1] + time.thread_time() - start[1]]
        return ready

    def finish(self, where: str = "the recording") -> list[np.ndarray]:
        """The poses of the frames still waiting (the recording has ended). InputError: no step moving
        with the road seen (no scale)."""
        return self._release(len(self.timestamps) - 1, where, final=True)

    def _release(self, last: int, where: str, final: bool = False) -> list[np.ndarray]:
        """The poses of the frames up to ``last`` not yet handed on, as far as they can be made final."""
        ready: list[np.ndarray] = []
        while len(self.poses) <= last:
            pose = self._pose(len(self.poses), where, final)
            if pose is None:
                break
            self.poses.append(pose)
            ready.append(pose)
        return ready

    def _pose(self, frame: int, where: str, final: bool) -> np.ndarray | None:
        """Frame ``frame``'s pose: its keyframe's, or between its keyframe and the next one (interpolated
        in time) when that is known; None while a step's length is not known yet."""
        key = int(np.searchsorted(self.key_frames, frame, side="right")) - 1
        if not self._fix(key, where, final):
            return None
        if self.key_frames[key] == frame or key + 1 >= len(self.key_frames):
            return self.key_poses[key]  # a frame after the newest keyframe: the image has not changed since
        if not self._fix(key + 1, where, final):
            return None
        t0, t1 = self.timestamps[self.key_frames[key]], self.timestamps[self.key_frames[key + 1]]
        pair = [self.key_poses[key], self.key_poses[key + 1]]
        between = EgoTrajectory(np.array([t0, t1]), np.array([p[:3, 3] for p in pair]),
                                np.array([rotation_to_quaternion(p[:3, :3]) for p in pair]))
        ego = between.at(self.timestamps[frame])
        assert ego is not None  # between its two keyframes
        pose = np.eye(4)
        pose[:3, :3], pose[:3, 3] = ego.rotation, ego.translation
        return pose

    def _fix(self, key: int, where: str, final: bool) -> bool:
        """Make the poses of the keyframes up to ``key`` final (their steps' lengths); False while a
        length cannot be known yet (no step measured by the road so far)."""
        if not self.key_poses:
            self.key_poses.append(np.eye(4))
        while len(self.key_poses) <= key:
            s = len(self.key_poses) - 1  # the step ending at keyframe s + 1
            step, filled = self.steps[s], False
            pitch = pooled_pitch(self.steps[max(0, s + 1 - PITCH_POOL_STEPS):])
            length = road_length(step, self.intrinsics, self.cam_to_vehicle, pitch)
            if np.isnan(length):
                length, filled = self._neighbours_length(s), True
                if np.isnan(length):
                    if final:
                        raise InputError(f"{where}: visual odometry saw no road ahead of the camera to give the "
                                         "motion its scale (check the calibration's cam_to_vehicle: the camera's "
                                         "height and pitch); give --ego-poses")
                    return False
            motion = chain_poses([step.rotation], [step.direction * length], self.cam_to_vehicle)[1]
            self.key_poses.append(self.key_poses[-1] @ motion)
            self.lengths.append(float(length))
            self.filled.append(filled)
            self.steps[s] = dataclasses.replace(step, road=(np.empty((0, 2)), np.empty((0, 2))))  # let them go
        return True

    def _duration(self, s: int) -> float:
        return self.timestamps[self.key_frames[s + 1]] - self.timestamps[self.key_frames[s]]

    def _neighbours_length(self, s: int) -> float:
        """Step ``s``'s length, metres, from the speed interpolated between the measured moving steps known now
        (:func:`~pedenv.odometry.motion.fill_lengths` over the final lengths before it, those from the
        neighbours' speed left out, and the steps' own after it); NaN without any."""
        lengths = np.array([n if not filled else np.nan for n, filled in zip(self.lengths, self.filled)]
                           + [np.nan] + [p.length for p in self.steps[s + 1:]])  # NaN: not measured
        if not np.any(lengths > 0):  # NaN compares False
            return float("nan")
        return float(fill_lengths(lengths, np.array([self._duration(i) for i in range(len(lengths))]))[s])

    def trajectory(self) -> EgoTrajectory | None:
        """The poses handed on, one a frame (None before the first), source :data:`ESTIMATED_SOURCE`."""
        if not self.poses:
            return None
        poses = np.array(self.poses)
        quats = np.array([rotation_to_quaternion(p[:3, :3]) for p in poses])
        return EgoTrajectory(np.array(self.timestamps[:len(poses)]), poses[:, :3, 3].copy(), quats, ESTIMATED_SOURCE)

    def report(self) -> dict[str, Any]:
        """``run.json``'s ``ego_poses`` of estimated poses: the file, the frames with a pose and the keyframes
        among them, the frames (each ending a step) whose length the road did not give (the neighbours' speed),
        whose length came from aligning the road (frames far apart) and whose motion from matched descriptors
        (the flow lost them), the lag and the time spent estimating (wall and CPU of the estimating thread,
        the decoding not counted: it is the frame loop's)."""
        frames = len(self.poses)
        ends = self.key_frames[1:len(self.lengths) + 1]  # step i ends at keyframe i + 1
        steps = self.steps[:len(self.lengths)]
        return {
            "source": "estimated", "file": ESTIMATED_SOURCE, "frames": frames,
            "keyframes": sum(1 for f in self.key_frames if f < frames),
            "frames_without_road_scale": [ends[i] for i, filled in enumerate(self.filled) if filled],
            "frames_scaled_by_road_alignment": [ends[i] for i, s in enumerate(steps) if s.guided],
            "frames_from_matched_descriptors": [ends[i] for i, s in enumerate(steps) if s.wide],
            "lag_frames": self.lag, "estimate_s": round(self.spent[0], 3), "estimate_cpu_s": round(self.spent[1], 3),
            "estimate_ms_per_frame": round(1e3 * self.spent[0] / max(len(self.timestamps), 1), 1),
        }
