"""The environment model of one frame as ROS 2 messages (built with :func:`pedenv.outputs.ros_types.make`).

Frames: ``world`` (the model's world frame) -> ``base_link`` (the vehicle) -> ``camera_optical``
(x right, y down, z forward). Each pedestrian is a body-sized box standing on its position:
``BODY_DIAMETER_M`` wide, as tall as its 3D skeleton reaches (head top, clipped to
``BODY_HEIGHT_RANGE_M``) or ``DEFAULT_BODY_HEIGHT_M`` without one.
"""

from __future__ import annotations

import uuid
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from pedenv.outputs.ros_types import Message, Typestore, make
from pedenv.skeleton import COCO_BONES
from pedenv.state import EnvironmentState

WORLD_FRAME, VEHICLE_FRAME, CAMERA_FRAME = "world", "base_link", "camera_optical"
CLASS_ID = "pedestrian"
AUTOWARE_PEDESTRIAN = 7  # autoware_perception_msgs/ObjectClassification.PEDESTRIAN
BODY_DIAMETER_M = 0.6
DEFAULT_BODY_HEIGHT_M = 1.7  # the paper's height prior
BODY_HEIGHT_RANGE_M = (1.0, 2.2)
HEAD_TOP_ABOVE_EYES_M = 0.12
#: Variance (m^2, rad^2, (m/s)^2) written for what the model does not estimate: z, orientation,
#: velocity and acceleration uncertainty. Large, so a consumer gives those components no weight.
UNKNOWN_VARIANCE = 1.0e4
#: A pedestrian slower than this (m/s) is ``is_stationary`` in Autoware's kinematics.
STATIONARY_SPEED_MPS = 0.2
#: Namespace of the UUIDs made from ``<scene>/<track id>`` (uuid5), stable over runs.
UUID_NAMESPACE = uuid.UUID("6d3b2f0e-4c1a-5b7e-9a2d-70656465e076")


def stamp(store: Typestore, ns: int) -> Message:
    return make(store, "builtin_interfaces/msg/Time", sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def header(store: Typestore, ns: int, frame: str = WORLD_FRAME) -> Message:
    return make(store, "std_msgs/msg/Header", stamp=stamp(store, ns), frame_id=frame)


def _point(store: Typestore, p: Sequence[float] | np.ndarray, kind: str = "geometry_msgs/msg/Point") -> Message:
    return make(store, kind, x=float(p[0]), y=float(p[1]), z=float(p[2]))


def _pose(store: Typestore, p: Sequence[float] | np.ndarray, rotation: np.ndarray | None = None) -> Message:
    x, y, z, w = (0.0, 0.0, 0.0, 1.0) if rotation is None else Rotation.from_matrix(rotation).as_quat()
    return make(store, "geometry_msgs/msg/Pose", position=_point(store, p),
                orientation=make(store, "geometry_msgs/msg/Quaternion", x=x, y=y, z=z, w=w))


def body_heights(state: EnvironmentState) -> np.ndarray:
    """(N,) metres: how tall each pedestrian's box is (module doc)."""
    p = state.pedestrians
    seen = (p.confidences > 0) & np.isfinite(p.keypoints_3d).all(axis=2)
    top = np.where(seen, p.keypoints_3d[..., 2], -np.inf).max(axis=1) if len(p) else np.zeros(0)
    height = top - p.positions[:, 2] + HEAD_TOP_ABOVE_EYES_M
    height = np.where(np.isfinite(height), height, DEFAULT_BODY_HEIGHT_M)
    return np.clip(height, *BODY_HEIGHT_RANGE_M)


def pose_covariance(cov_xy: np.ndarray) -> np.ndarray:
    """(36,) row-major 6x6 covariance (x, y, z, roll, pitch, yaw): the model's x-y block, the rest unknown."""
    cov = np.diag([0.0, 0.0] + [UNKNOWN_VARIANCE] * 4)
    cov[:2, :2] = cov_xy
    return cov.ravel()


def object_uuid(scene: str, track_id: int) -> bytes:
    """The 16 bytes of the pedestrian's UUID (uuid5 of ``<scene>/<track id>``)."""
    return uuid.uuid5(UUID_NAMESPACE, f"{scene}/{int(track_id)}").bytes


def transforms(store: Typestore, state: EnvironmentState, cam_to_vehicle: np.ndarray, ns: int) -> Message:
    """``tf2_msgs/TFMessage``: world -> base_link (the ego pose) and base_link -> camera_optical."""
    def tf(parent: str, child: str, translation: np.ndarray, rotation: np.ndarray) -> Message:
        x, y, z, w = Rotation.from_matrix(rotation).as_quat()
        q = make(store, "geometry_msgs/msg/Quaternion", x=x, y=y, z=z, w=w)
        t = make(store, "geometry_msgs/msg/Transform",
                 translation=_point(store, translation, "geometry_msgs/msg/Vector3"), rotation=q)
        return make(store, "geometry_msgs/msg/TransformStamped", header=header(store, ns, parent), child_frame_id=child,
                    transform=t)

    return make(store, "tf2_msgs/msg/TFMessage", transforms=[
        tf(WORLD_FRAME, VEHICLE_FRAME, state.ego.translation, state.ego.rotation),
        tf(VEHICLE_FRAME, CAMERA_FRAME, cam_to_vehicle[:3, 3], cam_to_vehicle[:3, :3])])


def _score(state: EnvironmentState, i: int) -> float:
    conf = state.pedestrians.confidences[i]
    return float(conf[conf > 0].mean()) if np.any(conf > 0) else 0.0


def detections(store: Typestore, state: EnvironmentState, ns: int) -> Message:
    """``vision_msgs/Detection3DArray`` in the world frame: one Detection3D per pedestrian."""
    p, heights = state.pedestrians, body_heights(state)
    items = []
    for i in range(len(p)):
        hypothesis = make(store, "vision_msgs/msg/ObjectHypothesisWithPose",
                          hypothesis=make(store, "vision_msgs/msg/ObjectHypothesis", class_id=CLASS_ID,
                                          score=_score(state, i)),
                          pose=make(store, "geometry_msgs/msg/PoseWithCovariance", pose=_pose(store, p.positions[i]),
                                    covariance=pose_covariance(p.covariances[i])))
        box = make(store, "vision_msgs/msg/BoundingBox3D", center=_pose(store, p.positions[i] + [0, 0, heights[i] / 2]),
                   size=_point(store, (BODY_DIAMETER_M, BODY_DIAMETER_M, heights[i]), "geometry_msgs/msg/Vector3"))
        items.append(make(store, "vision_msgs/msg/Detection3D", header=header(store, ns), results=[hypothesis],
                          bbox=box, id=str(int(p.track_ids[i]))))
    return make(store, "vision_msgs/msg/Detection3DArray", header=header(store, ns), detections=items)


def tracked_objects(store: Typestore, state: EnvironmentState, ns: int) -> Message:
    """``autoware_perception_msgs/TrackedObjects``: each pedestrian as a cylinder, its pose at the
    cylinder's centre (Autoware's convention), velocity in the twist (world axes: orientation unavailable)."""
    p, heights = state.pedestrians, body_heights(state)
    unknown = np.eye(6).ravel() * UNKNOWN_VARIANCE
    objects = []
    for i in range(len(p)):
        vel = p.velocities[i]
        twist = make(store, "geometry_msgs/msg/Twist", linear=_point(store, vel, "geometry_msgs/msg/Vector3"))
        kinematics = make(
            store, "autoware_perception_msgs/msg/TrackedObjectKinematics",
            pose_with_covariance=make(store, "geometry_msgs/msg/PoseWithCovariance",
                                      pose=_pose(store, p.positions[i] + [0, 0, heights[i] / 2]),
                                      covariance=pose_covariance(p.covariances[i])),
            twist_with_covariance=make(store, "geometry_msgs/msg/TwistWithCovariance", twist=twist, covariance=unknown),
            acceleration_with_covariance=make(store, "geometry_msgs/msg/AccelWithCovariance", covariance=unknown),
            orientation_availability=0, is_stationary=bool(np.hypot(vel[0], vel[1]) < STATIONARY_SPEED_MPS))
        shape = make(store, "autoware_perception_msgs/msg/Shape", type=1, dimensions=_point(
            store, (BODY_DIAMETER_M, BODY_DIAMETER_M, heights[i]), "geometry_msgs/msg/Vector3"))
        objects.append(make(
            store, "autoware_perception_msgs/msg/TrackedObject",
            object_id=make(store, "unique_identifier_msgs/msg/UUID",
                           uuid=np.frombuffer(object_uuid(state.scene, p.track_ids[i]), np.uint8)),
            existence_probability=_score(state, i), kinematics=kinematics, shape=shape,
            classification=[make(store, "autoware_perception_msgs/msg/ObjectClassification",
                                 label=AUTOWARE_PEDESTRIAN, probability=1.0)]))
    return make(store, "autoware_perception_msgs/msg/TrackedObjects", header=header(store, ns), objects=objects)


def markers(store: Typestore, state: EnvironmentState, ns: int) -> Message:
    """``visualization_msgs/MarkerArray`` for RViz: a DELETEALL, then per pedestrian its 3D skeleton
    (LINE_LIST), 2-sigma ellipse (LINE_STRIP), id (TEXT_VIEW_FACING) and velocity arrow (ARROW)."""
    from pedenv.visualize.shapes import covariance_ellipses

    p = state.pedestrians
    red = make(store, "std_msgs/msg/ColorRGBA", r=0.9, g=0.25, b=0.15, a=1.0)
    blue = make(store, "std_msgs/msg/ColorRGBA", r=0.15, g=0.4, b=0.9, a=1.0)
    out = [make(store, "visualization_msgs/msg/Marker", header=header(store, ns), action=3)]

    def marker(i: int, kind: str, n: int, color: Message, scale: Sequence[float],
               points: Iterable[Sequence[float] | np.ndarray] = (), **extra: Any) -> Message:
        return make(store, "visualization_msgs/msg/Marker", header=header(store, ns), ns=f"pedestrian/{kind}",
                    id=int(p.track_ids[i]), type=n, action=0, color=color, pose=_pose(store, (0, 0, 0)),
                    scale=_point(store, scale, "geometry_msgs/msg/Vector3"),
                    points=[_point(store, q) for q in points], **extra)

    for i in range(len(p)):
        pos, vel = p.positions[i], p.velocities[i]
        seen = p.confidences[i] > 0
        bones = [p.keypoints_3d[i, k] for a, b in COCO_BONES if seen[a] and seen[b] for k in (a, b)]
        ring = covariance_ellipses(pos[None, :2], p.covariances[i][None], sigma=2.0)[0]
        out.append(marker(i, "skeleton", 5, blue, (0.04, 0, 0), bones))
        out.append(marker(i, "ellipse", 4, red, (0.03, 0, 0), [(x, y, pos[2] + 0.02) for x, y in ring]))
        text = make(store, "visualization_msgs/msg/Marker", header=header(store, ns), ns="pedestrian/id",
                    id=int(p.track_ids[i]), type=9, action=0, color=red, text=str(int(p.track_ids[i])),
                    pose=_pose(store, pos + [0, 0, 2.1]), scale=_point(store, (0, 0, 0.4), "geometry_msgs/msg/Vector3"))
        out.append(text)
        out.append(marker(i, "velocity", 0, red, (0.06, 0.18, 0.25), [pos + [0, 0, 0.1], pos + vel + [0, 0, 0.1]]))
    return make(store, "visualization_msgs/msg/MarkerArray", markers=out)
