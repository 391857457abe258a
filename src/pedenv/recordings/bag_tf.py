"""The transform tree of a bag (``/tf_static``, ``/tf``) and the ego trajectory from it or from odometry.

A transform ``parent -> child`` maps points of the child frame into the parent frame (tf's
convention), so the chain camera -> ... -> vehicle is the camera-to-vehicle transform, and
vehicle -> ... -> world the ego pose. Static links are 4x4 matrices; dynamic links are
time series interpolated as the ego poses CSV is (linear position, slerp rotation).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from pedenv.errors import InputError
from pedenv.geometry import quaternion_to_rotation
from pedenv.recordings.bag_source import RosMessage
from pedenv.recordings.ego_poses import MAX_EGO_COORDINATE_M
from pedenv.recordings.footage import EgoTrajectory


def stamp_seconds(stamp: RosMessage) -> float:
    """A ROS time (``sec``, ``nanosec``) in seconds, correctly rounded (integer division)."""
    return (int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)) / 1_000_000_000


def _xyz(v: RosMessage) -> list[float]:
    return [float(v.x), float(v.y), float(v.z)]


def _wxyz(q: RosMessage) -> list[float]:
    return [float(q.w), float(q.x), float(q.y), float(q.z)]


def _check_position(what: str, xyz: list[float]) -> None:
    """InputError naming ``what`` when a coordinate is beyond :data:`MAX_EGO_COORDINATE_M`, as the ego poses CSV's."""
    for axis, value in zip("xyz", xyz):
        if abs(value) > MAX_EGO_COORDINATE_M:
            raise InputError(f"{what}.{axis} = {value:g} m is beyond {MAX_EGO_COORDINATE_M:g} m from the origin "
                             "(positions there have no millimetre precision)")


def pose_matrix(translation: Sequence[float] | np.ndarray, quaternion: Sequence[float] | np.ndarray) -> np.ndarray:
    """(4, 4) of a translation (3,) metres and a quaternion ``[w, x, y, z]``."""
    m = np.eye(4)
    m[:3, :3] = quaternion_to_rotation(quaternion)
    m[:3, 3] = translation
    return m


@dataclass
class _Series:
    """Samples of one dynamic link: seconds, (3,) translations, (4,) quaternions ``[w, x, y, z]``."""

    parent: str
    stamps: list[float] = field(default_factory=list)
    translations: list[list[float]] = field(default_factory=list)
    quaternions: list[list[float]] = field(default_factory=list)


@dataclass
class TransformTree:
    """Every link of ``/tf_static`` and ``/tf``: child frame -> its parent and transform(s)."""

    bag: str
    static: dict[str, tuple[str, np.ndarray]] = field(default_factory=dict)
    dynamic: dict[str, _Series] = field(default_factory=dict)

    def add(self, msg: RosMessage, *, static: bool, topic: str, index: int) -> None:
        """Add the transforms of one ``tf2_msgs/TFMessage``; a link whose samples go back in time,
        or a frame given two parents, raises InputError naming the topic and message index."""
        for tf in msg.transforms:
            parent, child = str(tf.header.frame_id).lstrip("/"), str(tf.child_frame_id).lstrip("/")
            where = f"{self.bag}: topic {topic} message {index}"
            if not parent or not child or parent == child:
                raise InputError(f"{where}: transform {parent!r} -> {child!r} needs two different frame names")
            known = self.parent_of(child)
            if known is not None and known != parent:
                raise InputError(f"{where}: frame {child!r} gets parent {parent!r} but already has {known!r}")
            t, q = _xyz(tf.transform.translation), _wxyz(tf.transform.rotation)
            if not np.all(np.isfinite(t + q)) or np.linalg.norm(q) < 1e-9:
                raise InputError(f"{where}: transform {parent!r} -> {child!r} is not finite or has a zero quaternion")
            _check_position(f"{where}: transform {parent!r} -> {child!r}: transform.translation", t)
            if static:
                self.static[child] = (parent, pose_matrix(t, q))  # scipy normalises, as the YAML's quaternion
                continue
            series = self.dynamic.setdefault(child, _Series(parent))
            stamp = stamp_seconds(tf.header.stamp)
            if series.stamps and stamp < series.stamps[-1]:
                raise InputError(f"{where}: stamps go backwards: {parent!r} -> {child!r} at {stamp:.9f} s "
                                 f"after {series.stamps[-1]:.9f} s")
            if series.stamps and stamp == series.stamps[-1]:
                continue  # a repeated sample (tf republishes); the first one counts
            series.stamps.append(stamp)
            series.translations.append(t)
            series.quaternions.append(q)

    def parent_of(self, frame: str) -> str | None:
        if frame in self.static:
            return self.static[frame][0]
        return self.dynamic[frame].parent if frame in self.dynamic else None

    def frames(self) -> list[str]:
        """Every frame named, sorted."""
        return sorted({*self.static, *self.dynamic, *(self.parent_of(f) or "" for f in {*self.static, *self.dynamic})}
                      - {""})

    def describe(self) -> str:
        """The links as ``parent->child`` (static ones marked), for error lines."""
        links = [f"{p}->{c} (static)" for c, (p, _) in self.static.items()]
        links += [f"{s.parent}->{c}" for c, s in self.dynamic.items()]
        return ", ".join(sorted(links)) or "no transforms"

    def chain(self, frame: str) -> list[str]:
        """``frame`` and its ancestors up to the root; a loop raises InputError."""
        path = [frame]
        while (parent := self.parent_of(path[-1])) is not None:
            if parent in path:
                raise InputError(f"{self.bag}: the tf tree has a loop: {' -> '.join(path + [parent])}")
            path.append(parent)
        return path

    def path(self, child: str, ancestor: str) -> list[str]:
        """The frames from ``child`` up to ``ancestor``; a missing link raises InputError listing the tree."""
        path = self.chain(child)
        if ancestor not in path:
            raise InputError(f"{self.bag}: no transform chain from {child!r} up to {ancestor!r} in /tf_static and "
                             f"/tf (a missing link?); {child!r} reaches {' -> '.join(path)}; the bag holds: "
                             f"{self.describe()}")
        return path[:path.index(ancestor) + 1]

    def static_transform(self, child: str, ancestor: str) -> np.ndarray:
        """(4, 4) child -> ancestor over static links (a dynamic one contributes its first sample)."""
        m = np.eye(4)
        for frame in self.path(child, ancestor)[:-1]:
            if frame in self.static:
                link = self.static[frame][1]
            else:
                s = self.dynamic[frame]
                link = pose_matrix(s.translations[0], s.quaternions[0])
            m = link @ m
        return m

    def trajectory(self, vehicle: str, world: str) -> EgoTrajectory:
        """The vehicle -> world poses: each sample of the link nearest the vehicle, the other
        links interpolated at its stamps (within the span they all cover)."""
        frames = self.path(vehicle, world)[:-1]
        moving = [f for f in frames if f in self.dynamic]
        if not moving:
            raise InputError(f"{self.bag}: the chain {' -> '.join(frames + [world])} has no link in /tf, so the "
                             "vehicle never moves; give --odometry-topic, or check the frames")
        links = {f: _series_trajectory(self.dynamic[f], f"{self.bag} /tf {self.dynamic[f].parent}->{f}")
                 for f in moving}
        base = links[moving[0]]
        if len(frames) == 1:
            return base
        stamps = [t for t in base.timestamps if all(tr.at(t) is not None for tr in links.values())]
        if not stamps:
            raise InputError(f"{self.bag}: the /tf links {', '.join(moving)} cover no common time span")
        poses = []
        for t in stamps:
            m = np.eye(4)
            for f in frames:
                pose = None if f in self.static else links[f].at(t)
                link = self.static[f][1] if pose is None else pose.matrix
                m = link @ m
            poses.append(m)
        return _matrix_trajectory(np.array(stamps), np.array(poses), f"{self.bag} /tf {world}->{vehicle}")


def _series_trajectory(series: _Series, source: str) -> EgoTrajectory:
    q = np.array(series.quaternions)
    return EgoTrajectory(np.array(series.stamps), np.array(series.translations),
                         q / np.linalg.norm(q, axis=1)[:, None], source)


def _matrix_trajectory(stamps: np.ndarray, poses: np.ndarray, source: str) -> EgoTrajectory:
    from scipy.spatial.transform import Rotation

    quats = Rotation.from_matrix(poses[:, :3, :3]).as_quat(canonical=True, scalar_first=True)
    return EgoTrajectory(stamps, poses[:, :3, 3], quats, source)


def odometry_trajectory(messages: Iterable[tuple[int, RosMessage]], bag: str,
                        topic: str) -> tuple[EgoTrajectory, str, str]:
    """The ego trajectory of ``nav_msgs/Odometry`` messages (``(index, msg)`` pairs) with their
    world (``header.frame_id``) and vehicle (``child_frame_id``) frames."""
    series = _Series("")
    child = ""
    for index, msg in messages:
        where = f"{bag}: topic {topic} message {index}"
        stamp = stamp_seconds(msg.header.stamp)
        series.parent, child = str(msg.header.frame_id).lstrip("/"), str(msg.child_frame_id).lstrip("/")
        t, q = _xyz(msg.pose.pose.position), _wxyz(msg.pose.pose.orientation)
        if not np.all(np.isfinite(t + q)) or np.linalg.norm(q) < 1e-9:
            raise InputError(f"{where}: the pose is not finite or has a zero quaternion")
        _check_position(f"{where}: pose.pose.position", t)
        if series.stamps and stamp < series.stamps[-1]:
            raise InputError(f"{where}: stamps go backwards: {stamp:.9f} s after {series.stamps[-1]:.9f} s")
        if series.stamps and stamp == series.stamps[-1]:
            continue
        series.stamps.append(stamp)
        series.translations.append(t)
        series.quaternions.append(q)
    if not series.stamps:
        raise InputError(f"{bag}: topic {topic} holds no odometry message")
    return _series_trajectory(series, f"{bag} {topic}"), series.parent, child
