"""A ROS bag as a ``pedenv run`` recording: images, CameraInfo, /tf_static, /tf or odometry -> Frames.

The same :class:`~pedenv.records.Frame` stream an image folder + calibration YAML + ego
poses CSV gives (:mod:`pedenv.recordings.footage`): each image's ``header.stamp`` is its
timestamp, the camera comes from ``CameraInfo`` (distorted images are undistorted onto the
same K), the camera-to-vehicle transform from the tf chain camera frame -> vehicle frame, and
the ego pose is the chain vehicle -> world interpolated at the stamp (or ``nav_msgs/Odometry``).
Topics and frames are found when there is one obvious choice (:func:`choose_topics`).
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from pedenv.errors import InputError
from pedenv.recordings.bag_images import CAMERA_INFO_TYPE, CameraModel, Undistorter, camera_model, image_rgb
from pedenv.recordings.bag_source import MAX_MESSAGE_BYTES, BagSource
from pedenv.recordings.bag_tf import TransformTree, odometry_trajectory, stamp_seconds
from pedenv.recordings.bag_topics import BagChoice, BagOptions, choose_frames, choose_topics
from pedenv.recordings.calibration_fields import MAX_MOUNT_DISTANCE_M
from pedenv.recordings.footage import EgoTrajectory
from pedenv.records import Camera, Frame

__all__ = ["BagOptions", "BagRecording", "load_bag_recording"]


@dataclass(frozen=True)
class BagRecording:
    """One bag as a recording: the camera, the ego trajectory and the image topic to stream.

    choice: the topics and frames used. camera_model: CameraInfo's camera (with distortion).
    """

    name: str
    path: Path
    camera: Camera
    trajectory: EgoTrajectory
    choice: BagChoice
    camera_model: CameraModel
    frames_total: int
    max_message_bytes: int = MAX_MESSAGE_BYTES
    video: None = None
    images: tuple = ()
    fps: float | None = None
    #: Why the bag gives fewer frames than announced (storage counts that disagree with
    #: metadata.yaml, images that ended before the count), or empty: a line each, also warned.
    shortfall: list[str] = field(default_factory=list, compare=False)

    def __len__(self) -> int:
        return self.frames_total

    @property
    def ended_early(self) -> str | None:
        """What the bag lacks of what it announces (``run.json``'s ``ended_early``), or None."""
        return "; ".join(self.shortfall) or None

    def frames(self) -> Iterator[Frame]:
        """The frames in order, images decoded (RGB, undistorted) and ego poses interpolated.

        Raises :class:`InputError` naming the bag, topic and message index at the first image
        that is undecodable, not the CameraInfo's size, earlier than the one before, or
        without an ego pose; the frames before it were yielded.
        """
        topic = self.choice.image_topic
        done = 0
        undistort = Undistorter(self.camera_model) if self.camera_model.distorted else None
        previous = None
        with BagSource(self.path, max_message_bytes=self.max_message_bytes) as bag:
            msgtype = bag.topics[topic].msgtype
            for m in bag.messages([topic]):
                where = f"{self.path}: topic {topic} message {m.index}"
                stamp = stamp_seconds(m.msg.header.stamp)
                if previous is not None and stamp <= previous:
                    raise InputError(f"{where}: stamps go backwards: {stamp:.9f} s is not after the previous "
                                     f"image's {previous:.9f} s")
                previous = stamp
                try:
                    image = image_rgb(m.msg, msgtype, (self.camera.width, self.camera.height))
                except InputError as exc:
                    raise InputError(f"{where}: {exc}") from None
                ego = self.trajectory.at(stamp)
                if ego is None:
                    span = self.trajectory.timestamps
                    raise InputError(f"{where}: the image at {stamp:.9f} s has no ego pose: {self.trajectory.source} "
                                     f"covers {span[0]:.9f} s to {span[-1]:.9f} s")
                done += 1
                yield Frame(m.index, stamp, self.camera, ego, image=undistort(image) if undistort else image,
                            scene=self.name)
        if done < self.frames_total:
            text = f"{self.path}: topic {topic} ended after {done} of the {self.frames_total} images the bag counts"
            self.shortfall.append(text)
            warnings.warn(text, stacklevel=2)


def load_bag_recording(path: str | Path, options: BagOptions | None = None, name: str | None = None) -> BagRecording:
    """Read a bag's camera, transforms and ego poses (every message but the images) and
    choose its topics and frames (``options`` overrides the choice; module doc)."""
    opts = options or BagOptions()
    path = Path(path)
    with BagSource(path, max_message_bytes=opts.max_message_bytes) as bag:
        topics = choose_topics(bag, opts)
        tree = TransformTree(str(path))
        info_msg, odometry = None, []
        wanted = [*topics.tf_topics, topics.camera_info_topic, *([topics.odometry_topic] if topics.odometry_topic
                                                                  else [])]
        for m in bag.messages(wanted, to_the_cut=True):
            if m.topic == topics.camera_info_topic:
                info_msg = info_msg or (m.index, m.msg)
            elif m.topic == topics.odometry_topic:
                odometry.append((m.index, m.msg))
            else:
                tree.add(m.msg, static=m.topic.endswith("tf_static"), topic=m.topic, index=m.index)
        if info_msg is None:
            raise InputError(f"{path}: topic {topics.camera_info_topic} holds no {CAMERA_INFO_TYPE} message")
        try:
            model = camera_model(info_msg[1])
        except InputError as exc:
            raise InputError(f"{path}: topic {topics.camera_info_topic} message {info_msg[0]}: {exc}") from None
        frames_total = bag.topics[topics.image_topic].count
        shortfall = [bag.counts_differ] if bag.counts_differ else []
        if bag.counts_differ:
            warnings.warn(bag.counts_differ, stacklevel=2)
    moving = any(f in tree.dynamic for f in tree.chain(model.frame_id.lstrip("/")))
    use_odometry = topics.odometry_topic is not None and (opts.odometry_topic is not None or not moving)
    odom_world = odom_vehicle = None
    if use_odometry:
        trajectory, odom_world, odom_vehicle = odometry_trajectory(odometry, str(path), topics.odometry_topic or "")
    else:
        topics = replace(topics, odometry_topic=None)
    choice = choose_frames(tree, topics, model.frame_id, opts, odom_world, odom_vehicle)
    if not use_odometry:
        trajectory = tree.trajectory(choice.vehicle_frame, choice.world_frame)
    cam_to_vehicle = tree.static_transform(choice.camera_frame, choice.vehicle_frame)
    _check_mount(path, choice, cam_to_vehicle)
    try:
        camera = Camera(model.intrinsics, model.width, model.height, cam_to_vehicle)
    except InputError as exc:
        raise InputError(f"{path}: camera {choice.camera_frame!r}: {exc}") from None
    return BagRecording(name or path.stem, path, camera, trajectory, choice, model, frames_total,
                        opts.max_message_bytes, shortfall=shortfall)


#: Steepest a camera may look up or down from the vehicle's horizon, degrees: road cameras look
#: within about 30 degrees of it; a camera looking straight up or down (90) means the vehicle frame
#: is not x forward, z up (REP 103), e.g. ``--vehicle-frame`` naming a camera's optical frame.
MAX_CAMERA_TILT_DEG = 60.0


def _check_mount(path: Path, choice: BagChoice, cam_to_vehicle: np.ndarray) -> None:
    """InputError when the tf chain puts the camera farther from the vehicle origin than a YAML
    calibration may (:data:`~pedenv.recordings.calibration_fields.MAX_MOUNT_DISTANCE_M`) or tilts it
    beyond :data:`MAX_CAMERA_TILT_DEG`."""
    where = f"{path}: the tf chain {choice.camera_frame} -> {choice.vehicle_frame}"
    distance = float(np.linalg.norm(cam_to_vehicle[:3, 3]))
    if distance > MAX_MOUNT_DISTANCE_M:
        raise InputError(f"{where} puts the camera {distance:g} m from the vehicle origin; at most "
                         f"{MAX_MOUNT_DISTANCE_M:g} m (is {choice.vehicle_frame!r} the vehicle? --vehicle-frame)")
    tilt = float(np.degrees(np.arcsin(np.clip(cam_to_vehicle[2, 2], -1.0, 1.0))))
    if abs(tilt) > MAX_CAMERA_TILT_DEG:
        raise InputError(f"{where} has the camera look {abs(tilt):.0f} degrees {'up' if tilt > 0 else 'down'} "
                         f"from the vehicle's horizon; at most {MAX_CAMERA_TILT_DEG:g} (the vehicle frame must be "
                         f"x forward, z up: is {choice.vehicle_frame!r} the vehicle? --vehicle-frame)")
