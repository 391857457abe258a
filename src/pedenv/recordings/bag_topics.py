"""Which topics and frames of a bag a run uses: the one obvious choice, or the user's.

An ambiguous or missing choice raises one :class:`~pedenv.errors.InputError` line listing
what the bag holds and the flag that settles it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import PurePosixPath

from pedenv.errors import InputError
from pedenv.recordings.bag_images import CAMERA_INFO_TYPE, COMPRESSED_TYPE, IMAGE_TYPE
from pedenv.recordings.bag_source import MAX_MESSAGE_BYTES, BagSource
from pedenv.recordings.bag_tf import TransformTree

TF_TYPE = "tf2_msgs/msg/TFMessage"
ODOMETRY_TYPE = "nav_msgs/msg/Odometry"


@dataclass(frozen=True)
class BagOptions:
    """The user's choices for a bag (None: found from the bag).

    image_topic: ``sensor_msgs/Image`` or ``CompressedImage`` topic. camera_info_topic: its
    ``CameraInfo``. odometry_topic: ``nav_msgs/Odometry`` for the ego poses instead of /tf.
    world_frame, vehicle_frame: tf frame names (vehicle: x forward, y left, z up, on the road).
    max_message_bytes: larger messages are refused as corrupt (:data:`MAX_MESSAGE_BYTES`).
    """

    image_topic: str | None = None
    camera_info_topic: str | None = None
    odometry_topic: str | None = None
    world_frame: str | None = None
    vehicle_frame: str | None = None
    max_message_bytes: int = MAX_MESSAGE_BYTES


@dataclass(frozen=True)
class BagChoice:
    """The topics and frames a run uses ('' for a frame not chosen yet)."""

    image_topic: str
    camera_info_topic: str
    odometry_topic: str | None
    tf_topics: tuple[str, ...]
    camera_frame: str = ""
    vehicle_frame: str = ""
    world_frame: str = ""


def _holds(bag: BagSource) -> str:
    return "; ".join(f"{t.name} ({t.msgtype.replace('/msg/', '/')}, {t.count})" for t in bag.topics.values()) or \
        "no topics"


def _pick(bag: BagSource, given: str | None, types: tuple[str, ...], what: str, flag: str,
          prefer: str | None = None) -> str:
    found = bag.topics_of(*types)
    if given is not None:
        if given not in bag.topics or bag.topics[given].msgtype not in types:
            raise InputError(f"{bag.path}: {flag} {given} is not one of the bag's {what} topics; it holds: "
                             f"{_holds(bag)}")
        return given
    if len(found) > 1 and prefer is not None and prefer in found:
        return prefer
    if len(found) > 1 and what == "image":  # the same camera raw and compressed: the raw images
        raw = [t for t in found if t + "/compressed" in found]
        if len(raw) == 1 and len(found) == 2:
            return raw[0]
    if len(found) != 1:
        how = "no" if not found else f"{len(found)}"
        raise InputError(f"{bag.path}: {how} {what} topics, give {flag}; the bag holds: {_holds(bag)}")
    return found[0]


def choose_topics(bag: BagSource, opts: BagOptions) -> BagChoice:
    """The image, CameraInfo, odometry and tf topics of ``bag`` (a :class:`BagSource`)."""
    image = _pick(bag, opts.image_topic, (IMAGE_TYPE, COMPRESSED_TYPE), "image", "--image-topic")
    if bag.topics[image].count == 0:
        raise InputError(f"{bag.path}: topic {image} holds no image; the bag holds: {_holds(bag)}")
    base = str(PurePosixPath(image).parent)
    base = str(PurePosixPath(base).parent) if image.endswith("/compressed") else base
    info = _pick(bag, opts.camera_info_topic, (CAMERA_INFO_TYPE,), "CameraInfo", "--camera-info-topic",
                 prefer=f"{base.rstrip('/')}/camera_info")
    odometry = None  # the one odometry topic is read too: it gives the ego poses when no /tf link moves
    if opts.odometry_topic is not None or len(bag.topics_of(ODOMETRY_TYPE)) == 1:
        odometry = _pick(bag, opts.odometry_topic, (ODOMETRY_TYPE,), "odometry", "--odometry-topic")
    tf = tuple(bag.topics_of(TF_TYPE))
    return BagChoice(image, info, odometry, tf)


def choose_frames(tree: TransformTree, topics: BagChoice, camera_frame: str, opts: BagOptions, odom_world: str | None,
                  odom_vehicle: str | None) -> BagChoice:
    """The camera, vehicle and world frames: the vehicle is the frame the camera hangs from over
    static links (just below the first /tf link up from the camera), the world the root above it;
    with odometry, its ``child_frame_id`` and ``frame_id``."""
    camera_frame = camera_frame.lstrip("/")
    if not camera_frame:
        raise InputError(f"{tree.bag}: {topics.camera_info_topic} has no header.frame_id: the camera's tf frame "
                         "is unknown")
    chain = tree.chain(camera_frame)
    if len(chain) == 1:
        raise InputError(f"{tree.bag}: the camera frame {camera_frame!r} ({topics.camera_info_topic}) has no "
                         f"transform in /tf_static or /tf; the bag holds: {tree.describe()}")
    for flag, given, odom, field in (("--world-frame", opts.world_frame, odom_world, "header.frame_id"),
                                     ("--vehicle-frame", opts.vehicle_frame, odom_vehicle, "child_frame_id")):
        if given is not None and odom is not None and given != odom:
            raise InputError(f"{tree.bag}: {flag} {given}, but the poses of {topics.odometry_topic} are of "
                             f"{odom!r} ({field}); leave out {flag} or give another --odometry-topic")
    vehicle = opts.vehicle_frame or odom_vehicle
    if vehicle is None:
        moving = [f for f in chain if f in tree.dynamic]
        if not moving:
            raise InputError(f"{tree.bag}: no /tf link moves the camera ({' -> '.join(chain)}); give "
                             f"--odometry-topic or --vehicle-frame and --world-frame")
        vehicle = moving[0]
    world = opts.world_frame or odom_world
    if world is None:
        world = tree.chain(vehicle)[-1]
    if vehicle == world:
        raise InputError(f"{tree.bag}: the vehicle frame and the world frame are both {vehicle!r}; give "
                         "--vehicle-frame or --world-frame")
    tree.path(camera_frame, vehicle)  # a missing link raises here, naming the frames
    return replace(topics, camera_frame=camera_frame, vehicle_frame=vehicle, world_frame=world)
