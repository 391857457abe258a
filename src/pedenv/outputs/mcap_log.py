"""The environment model as an MCAP file for Foxglove (foxglove-sdk), one message set per frame.

Topics (Foxglove schemas unless said otherwise), frames ``world`` -> ``ego`` -> ``camera``
(``camera`` is the optical frame: x right, y down, z forward):

* ``/tf``: ``FrameTransforms``, world -> ego (the ego pose) and ego -> camera (the mounting);
* ``/pedestrians``: ``SceneUpdate`` in ``world``, one entity ``ped-<track id>`` per pedestrian:
  a sphere at the position, a velocity arrow, the 3D skeleton (line list), the 2-sigma
  ellipse on the ground (line loop) and the id as text; each update first deletes all;
  with behaviour: a heading arrow, the predicted path with its ellipses (red in conflict);
* ``/ground_truth``: ``SceneUpdate`` with the true positions (where the frame is labelled);
* ``/ego``: ``SceneUpdate`` with the ego's path so far, entities ``ego-path-<piece>`` of 100
  positions each (:mod:`pedenv.outputs.ego_path`: the file grows linearly with the stream);
* ``/camera/calibration``: ``CameraCalibration``; ``/camera/image``: ``CompressedImage`` (JPEG, when
  the frame has an image); ``/camera/annotations``: ``ImageAnnotations`` (skeletons, boxes, ids);
* ``/environment``: JSON, ``EnvironmentState.to_dict()`` (the JSON Lines record).

Log times are the frame timestamps; a scene that starts earlier than the previous one ended is
shifted to start one second after it, so that a file of several scenes plays in order. The
file is finished (summary and index) by ``close()``; a run stopped by an exception closes it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path

import foxglove
import numpy as np
from foxglove import channels as fc
from foxglove import messages as fm

from pedenv.errors import InputError
from pedenv.outputs.ego_path import EgoPath
from pedenv.outputs.mcap_behaviour import ego_path_line, pedestrian_primitives
from pedenv.records import Frame
from pedenv.skeleton import COCO_BONES
from pedenv.state import EnvironmentState
from pedenv.visualize.behaviour_shapes import BehaviourShapes, behaviour_shapes
from pedenv.visualize.shapes import covariance_ellipses

_RED, _BLUE, _BLACK, _GREEN = (fm.Color(r=0.9, g=0.25, b=0.15, a=1.0), fm.Color(r=0.15, g=0.4, b=0.9, a=1.0),
                               fm.Color(r=0.1, g=0.1, b=0.1, a=1.0), fm.Color(r=0.15, g=0.65, b=0.25, a=1.0))


def _v3(p: Sequence[float] | np.ndarray) -> fm.Vector3:
    return fm.Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def _p3(p: Sequence[float] | np.ndarray) -> fm.Point3:
    return fm.Point3(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def _quaternion(r: np.ndarray) -> fm.Quaternion:
    """(3, 3) rotation matrix -> unit quaternion."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(r).as_quat()
    return fm.Quaternion(x=float(x), y=float(y), z=float(z), w=float(w))


def _pose(position: np.ndarray, yaw: float = 0.0) -> fm.Pose:
    """A pose at ``position`` (3,) metres, turned by ``yaw`` radians about z."""
    return fm.Pose(
        position=_v3(position), orientation=fm.Quaternion(z=float(np.sin(yaw / 2)), w=float(np.cos(yaw / 2)))
    )


#: Uncompressed bytes of an MCAP chunk (the writer's default is 768 KiB): what the file holds back in
#: memory and writes at once. Kept small so that the room a full disk is watched for
#: (:data:`pedenv.apps.output_safety.BUFFERED_BYTES`) covers it.
MCAP_CHUNK_BYTES = 256 * 1024


class McapWriter:
    """A :class:`pedenv.outputs.sinks.FrameSink` writing the topics above to one MCAP file."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._context = foxglove.Context()
        from foxglove.mcap import MCAPWriteOptions

        self._writer = foxglove.open_mcap(self.path, allow_overwrite=True, context=self._context,
                                          writer_options=MCAPWriteOptions(chunk_size=MCAP_CHUNK_BYTES))
        self._open_channels()

    def _open_channels(self) -> None:
        """The topics above in ``self._context`` (a file's or a live server's), and a fresh scene."""
        ctx = self._context
        self._tf = fc.FrameTransformsChannel("/tf", context=ctx)
        self._peds = fc.SceneUpdateChannel("/pedestrians", context=ctx)
        self._truth = fc.SceneUpdateChannel("/ground_truth", context=ctx)
        self._ego = fc.SceneUpdateChannel("/ego", context=ctx)
        self._calibration = fc.CameraCalibrationChannel("/camera/calibration", context=ctx)
        self._image = fc.CompressedImageChannel("/camera/image", context=ctx)
        self._annotations = fc.ImageAnnotationsChannel("/camera/annotations", context=ctx)
        self._environment = foxglove.Channel("/environment", message_encoding="json", context=ctx)
        self._scene: str | None = None
        self._offset = 0.0
        self._last = -np.inf
        self._trajectory = EgoPath()

    def write(self, state: EnvironmentState, frame: Frame) -> None:
        if state.scene != self._scene:
            self._scene, self._trajectory = state.scene, EgoPath()
            self._offset = 0.0 if state.timestamp > self._last else self._last + 1.0 - state.timestamp
        t = state.timestamp + self._offset
        self._last = t
        ns = int(round(t * 1e9))
        stamp = fm.Timestamp.from_epoch_secs(t)
        self._log_transforms(state, frame, stamp, ns)
        shapes = behaviour_shapes(state.pedestrians)
        self._peds.log(fm.SceneUpdate(deletions=[_delete_all(stamp)], entities=[
            _pedestrian(state, i, stamp, shapes) for i in range(len(state.pedestrians))]), log_time=ns)
        self._log_ground_truth(frame, stamp, ns)
        piece, points = self._trajectory.add(state.ego.translation)
        self._ego.log(fm.SceneUpdate(entities=[fm.SceneEntity(
            timestamp=stamp, frame_id="world", id=f"ego-path-{piece}",
            lines=[fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineStrip, thickness=0.15, color=_GREEN,
                                    points=[_p3(p) for p in points])]),
            fm.SceneEntity(timestamp=stamp, frame_id="world", id="ego-predicted-path",
                           lines=ego_path_line(shapes, float(state.ego.translation[2])))]), log_time=ns)
        self._log_camera(state, frame, stamp, ns)
        record = state.to_dict()
        record["log_time"] = t
        self._environment.log(json.dumps(record).encode(), log_time=ns)

    def close(self) -> None:
        """Finish the file; one InputError naming it when a write failed (a full disk: the writer logs
        the failure and refuses every later write, its summary too)."""
        if self._writer is not None:
            writer, self._writer = self._writer, None
            try:
                writer.close()
            except RuntimeError as exc:
                raise InputError(f"{self.path}: cannot be finished: {exc}") from None

    def _log_transforms(self, state: EnvironmentState, frame: Frame, stamp: fm.Timestamp, ns: int) -> None:
        mount = frame.camera.cam_to_vehicle
        self._tf.log(fm.FrameTransforms(transforms=[
            fm.FrameTransform(timestamp=stamp, parent_frame_id="world", child_frame_id="ego",
                              translation=_v3(state.ego.translation), rotation=_quaternion(state.ego.rotation)),
            fm.FrameTransform(timestamp=stamp, parent_frame_id="ego", child_frame_id="camera",
                              translation=_v3(mount[:3, 3]), rotation=_quaternion(mount[:3, :3])),
        ]), log_time=ns)

    def _log_ground_truth(self, frame: Frame, stamp: fm.Timestamp, ns: int) -> None:
        gt = frame.ground_truth
        entities = (
            []
            if gt is None
            else [
                fm.SceneEntity(
                    timestamp=stamp,
                    frame_id="world",
                    id=f"gt-{int(i)}",
                    spheres=[
                        fm.SpherePrimitive(
                            pose=_pose(p + [0, 0, 0.2]), size=fm.Vector3(x=0.3, y=0.3, z=0.3), color=_BLACK
                        )
                    ],
                    texts=[
                        fm.TextPrimitive(
                            pose=_pose(p + [0, 0, 2.3]),
                            billboard=True,
                            font_size=0.3,
                            color=_BLACK,
                            text=f"gt {int(i)}",
                        )
                    ],
                )
                for i, p in zip(gt.ids, gt.positions)
            ]
        )
        self._truth.log(fm.SceneUpdate(deletions=[_delete_all(stamp)], entities=entities), log_time=ns)

    def _log_camera(self, state: EnvironmentState, frame: Frame, stamp: fm.Timestamp, ns: int) -> None:
        cam = frame.camera
        k = cam.intrinsics
        p = np.hstack([k, np.zeros((3, 1))])
        self._calibration.log(fm.CameraCalibration(
            timestamp=stamp, frame_id="camera", width=cam.width, height=cam.height, distortion_model="plumb_bob",
            D=[0.0] * 5, K=k.ravel().tolist(), R=np.eye(3).ravel().tolist(), P=p.ravel().tolist()), log_time=ns)
        data = _image_bytes(frame)
        if data is not None:
            self._image.log(fm.CompressedImage(timestamp=stamp, frame_id="camera", data=data[0], format=data[1]),
                            log_time=ns)
        self._annotations.log(_image_annotations(state, stamp), log_time=ns)


def _delete_all(stamp: fm.Timestamp) -> fm.SceneEntityDeletion:
    return fm.SceneEntityDeletion(timestamp=stamp, type=fm.SceneEntityDeletionType.All)


def _pedestrian(state: EnvironmentState, i: int, stamp: fm.Timestamp,
                shapes: BehaviourShapes | None = None) -> fm.SceneEntity:
    """Pedestrian ``i`` as one entity: sphere, velocity arrow, skeleton, 2-sigma ellipse, id text,
    and with behaviour (``shapes``) the heading arrow and predicted path (:mod:`pedenv.outputs.mcap_behaviour`)."""
    extra_arrows, extra_lines = pedestrian_primitives(state, shapes, i)
    p = state.pedestrians
    pos, vel = p.positions[i], p.velocities[i]
    speed = float(np.hypot(vel[0], vel[1]))
    arrows = [fm.ArrowPrimitive(pose=_pose(pos + [0, 0, 0.1], float(np.arctan2(vel[1], vel[0]))),
                                shaft_length=speed, shaft_diameter=0.06, head_length=0.25, head_diameter=0.18,
                                color=_RED)] if speed > 1e-3 else []
    seen = p.confidences[i] > 0
    bones = [k for a, b in COCO_BONES if seen[a] and seen[b] for k in (a, b)]
    ring = covariance_ellipses(pos[None, :2], p.covariances[i][None], sigma=2.0)[0, :-1]
    return fm.SceneEntity(
        timestamp=stamp, frame_id="world", id=f"ped-{int(p.track_ids[i])}",
        spheres=[fm.SpherePrimitive(pose=_pose(pos + [0, 0, 0.2]), size=fm.Vector3(x=0.4, y=0.4, z=0.4), color=_RED)],
        arrows=arrows + extra_arrows,
        lines=[fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineList, thickness=0.04, color=_BLUE,
                                points=[_p3(p.keypoints_3d[i, k]) for k in bones]),
               fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineLoop, thickness=0.03, color=_RED,
                                points=[_p3((x, y, pos[2] + 0.02)) for x, y in ring])] + extra_lines,
        texts=[fm.TextPrimitive(pose=_pose(pos + [0, 0, 2.1]), billboard=True, font_size=0.4, color=_RED,
                                text=str(int(p.track_ids[i])))])


def _image_annotations(state: EnvironmentState, stamp: fm.Timestamp) -> fm.ImageAnnotations:
    """2D skeletons (line lists), boxes (line loops) and track ids over the camera image."""
    p = state.pedestrians
    points, texts = [], []
    for i in range(len(p)):
        seen = p.confidences[i] > 0
        kp = p.keypoints[i]
        bones = [fm.Point2(x=float(kp[k, 0]), y=float(kp[k, 1])) for a, b in COCO_BONES if seen[a] and seen[b]
                 for k in (a, b)]
        points.append(fm.PointsAnnotation(timestamp=stamp, type=fm.PointsAnnotationType.LineList, points=bones,
                                          outline_color=_BLUE, thickness=2.0))
        u0, v0, u1, v1 = (float(x) for x in p.boxes[i])
        points.append(fm.PointsAnnotation(
            timestamp=stamp, type=fm.PointsAnnotationType.LineLoop, outline_color=_RED, thickness=2.0,
            points=[fm.Point2(x=u0, y=v0), fm.Point2(x=u1, y=v0), fm.Point2(x=u1, y=v1), fm.Point2(x=u0, y=v1)]))
        texts.append(fm.TextAnnotation(timestamp=stamp, position=fm.Point2(x=u0, y=max(v0 - 4.0, 0.0)),
                                       text=f"{int(p.track_ids[i])}  {float(p.distances[i]):.1f} m", font_size=18.0,
                                       text_color=_RED, background_color=fm.Color(r=1, g=1, b=1, a=0.7)))
    return fm.ImageAnnotations(timestamp=stamp, points=points, texts=texts)


def _image_bytes(frame: Frame) -> tuple[bytes, str] | None:
    """The frame's image as (bytes, "jpeg" or "png"): the file itself when it is one, else encoded."""
    if frame.image_path is not None and Path(frame.image_path).suffix.lower() in (".jpg", ".jpeg", ".png") \
            and Path(frame.image_path).is_file():
        suffix = Path(frame.image_path).suffix.lower()
        return Path(frame.image_path).read_bytes(), "png" if suffix == ".png" else "jpeg"
    if frame.image is not None:
        from pedenv.outputs.rerun_log import jpeg_bytes

        return jpeg_bytes(frame.image), "jpeg"
    return None
