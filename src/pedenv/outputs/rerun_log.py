"""The environment model as a Rerun recording (``.rrd``, rerun-sdk 0.23), one recording per scene.

Entities, on the timelines ``frame`` (the frame index) and ``time`` (seconds):

* ``world``: right-handed, z up, metres. ``world/ego`` (vehicle -> world transform) and
  ``world/ego/camera`` (camera -> vehicle transform, a pinhole: the frustum in 3D, the image in 2D);
* ``world/ego/camera/image``: the camera image (when the frame has one), ``boxes`` (with the
  track ids) and ``skeletons/<track id>`` (2D COCO-17 keypoints);
* ``world/ego_trajectory/<piece>``: the ego's path so far, in pieces of 100 positions
  (:mod:`pedenv.outputs.ego_path`: the file grows linearly with the stream);
* ``world/pedestrians``: ``positions`` (labelled with the track ids), ``velocities`` (arrows),
  ``ellipses`` (2-sigma outlines on the ground), ``skeletons/<track id>`` (3D keypoints);
* ``world/behaviour``: heading arrows, predicted paths with ellipses, conflict in red
  (:mod:`pedenv.outputs.rerun_behaviour`);
* ``world/ground_truth/positions`` and ``world/ego/camera/image/ground_truth`` (boxes) where labelled.

Skeleton lines come from the annotation context logged at ``/``: class 0 "person" with the
COCO-17 keypoints and connections. A person who leaves is cleared at that frame.

One scene gives ``FILE.rrd``; several give ``FILE-<scene>.rrd`` each (0.23's reader takes one
recording per file). The recording is flushed after every frame: a run stopped by an exception
keeps every finished frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow as pa
import rerun as rr

from pedenv.outputs.ego_path import EgoPath
from pedenv.outputs.rerun_behaviour import log_behaviour
from pedenv.records import Frame
from pedenv.skeleton import COCO_BONES, KEYPOINT_NAMES
from pedenv.state import EnvironmentState
from pedenv.visualize.shapes import covariance_ellipses

APPLICATION_ID = "pedenv"
PERSON_CLASS = 0
_PRED, _TRUTH, _EGO = (230, 60, 40), (30, 30, 30), (40, 160, 60)


def annotation_context() -> rr.AnnotationContext:
    """Class 0 "person" with the COCO-17 keypoint names and the limbs between them.

    Built as the component's Arrow array: rerun-sdk 0.23's ``ClassDescription`` objects call
    ``np.asarray(..., copy=)``, which numpy 1 lacks, and would be dropped with a warning.
    """
    r, g, b = _PRED
    description = {
        "info": {"id": PERSON_CLASS, "label": "person", "color": (r << 24) | (g << 16) | (b << 8) | 255},
        "keypoint_annotations": [{"id": i, "label": n, "color": None} for i, n in enumerate(KEYPOINT_NAMES)],
        "keypoint_connections": [{"keypoint0": int(a), "keypoint1": int(b)} for a, b in COCO_BONES],
    }
    array = pa.array([[{"class_id": PERSON_CLASS, "class_description": description}]],
                     type=rr.components.AnnotationContextBatch._ARROW_DATATYPE)
    return rr.AnnotationContext.from_fields(context=array)


def jpeg_bytes(image: np.ndarray, quality: int = 90) -> bytes:
    """(H, W, 3) uint8 RGB -> JPEG bytes."""
    import cv2

    ok, data = cv2.imencode(".jpg", cv2.cvtColor(image, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise ValueError(f"cannot encode a {image.shape} image as JPEG")
    return data.tobytes()


class RerunWriter:
    """A :class:`pedenv.outputs.sinks.FrameSink` writing one Rerun recording per scene."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.files: list[Path] = []
        self._rec: rr.RecordingStream | None = None
        self._scene: str | None = None
        self._scenes: list[str] = []
        self._trajectory = EgoPath()
        self._shown: set[int] = set()

    def write(self, state: EnvironmentState, frame: Frame) -> None:
        if self._rec is None or state.scene != self._scene:
            self._start(state.scene, frame)
        rec = self._rec
        assert rec is not None  # _start() made it
        rec.set_time("frame", sequence=int(state.frame_index))
        rec.set_time("time", duration=float(state.timestamp))
        self._log_ego(rec, state)
        self._log_image(rec, state, frame)
        self._log_world(rec, state)
        log_behaviour(rec, state)
        self._log_ground_truth(rec, frame)
        rec.flush(blocking=True)

    def close(self) -> None:
        self._finish()

    def _start(self, scene: str, frame: Frame) -> None:
        self._finish()
        self._scenes.append(scene)
        if len(self._scenes) == 2:  # several scenes: the first file gets its scene's name too
            first = self._scene_path(self._scenes[0])
            self.path.replace(first)
            self.files[0] = first
        path = self.path if len(self._scenes) == 1 else self._scene_path(scene)
        label = (scene or "scene").encode("utf-8", "backslashreplace").decode()  # a non-UTF-8 video name
        rec = rr.RecordingStream(APPLICATION_ID, recording_id=f"{APPLICATION_ID}-{label}")
        rec.save(path)
        rec.send_recording_name(label)
        rec.log("/", annotation_context(), static=True)
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        cam = frame.camera
        rec.log("world/ego/camera", rr.Transform3D(translation=cam.cam_to_vehicle[:3, 3],
                                                   mat3x3=cam.cam_to_vehicle[:3, :3]), static=True)
        rec.log(
            "world/ego/camera/image",
            rr.Pinhole(
                image_from_camera=cam.intrinsics,
                resolution=[cam.width, cam.height],
                camera_xyz=rr.ViewCoordinates.RDF,
                image_plane_distance=2.0,
            ),
            static=True,
        )
        self.files.append(path)
        self._rec, self._scene, self._trajectory, self._shown = rec, scene, EgoPath(), set()

    def _scene_path(self, scene: str) -> Path:
        safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in scene) or "scene"
        return self.path.with_name(f"{self.path.stem}-{safe}{self.path.suffix}")

    def _finish(self) -> None:
        if self._rec is not None:
            self._rec.flush(blocking=True)
            self._rec.disconnect()
            self._rec = None

    def _log_ego(self, rec: rr.RecordingStream, state: EnvironmentState) -> None:
        rec.log("world/ego", rr.Transform3D(translation=state.ego.translation, mat3x3=state.ego.rotation))
        piece, points = self._trajectory.add(state.ego.translation)
        rec.log(f"world/ego_trajectory/{piece}", rr.LineStrips3D([points], colors=[_EGO]))

    def _log_image(self, rec: rr.RecordingStream, state: EnvironmentState, frame: Frame) -> None:
        base = "world/ego/camera/image"
        if frame.image is not None:  # JPEG: a raw 1600x900 frame would be 4 MB
            rec.log(base, rr.EncodedImage(contents=jpeg_bytes(frame.image), media_type="image/jpeg"))
        elif frame.image_path is not None and Path(frame.image_path).is_file():
            rec.log(base, rr.EncodedImage(path=frame.image_path))
        p = state.pedestrians
        labels = [str(t) for t in p.track_ids]
        # show_labels: the viewer hides labels of a busy entity by default; the ids are the point here
        rec.log(f"{base}/boxes", rr.Boxes2D(array=p.boxes, array_format=rr.Box2DFormat.XYXY, labels=labels,
                                            class_ids=np.full(len(p), PERSON_CLASS), show_labels=True))
        self._log_skeletons(rec, f"{base}/skeletons", p.track_ids, p.keypoints, p.confidences, rr.Points2D)

    def _log_world(self, rec: rr.RecordingStream, state: EnvironmentState) -> None:
        p = state.pedestrians
        labels = [str(t) for t in p.track_ids]
        rec.log("world/pedestrians/positions", rr.Points3D(p.positions, labels=labels, radii=0.25, colors=[_PRED],
                                                           show_labels=True))
        rec.log("world/pedestrians/velocities", rr.Arrows3D(origins=p.positions, vectors=p.velocities, colors=[_PRED]))
        rings = covariance_ellipses(p.positions[:, :2], p.covariances, sigma=2.0)
        ground = np.concatenate([rings, np.broadcast_to(p.positions[:, None, 2:3], rings.shape[:2] + (1,))], axis=2)
        rec.log("world/pedestrians/ellipses", rr.LineStrips3D(list(ground), colors=[_PRED]))
        self._log_skeletons(rec, "world/pedestrians/skeletons", p.track_ids, p.keypoints_3d, p.confidences,
                            rr.Points3D)
        gone = self._shown - {int(t) for t in p.track_ids}
        for tid in gone:
            rec.log(f"world/pedestrians/skeletons/{tid}", rr.Clear(recursive=True))
            rec.log(f"world/ego/camera/image/skeletons/{tid}", rr.Clear(recursive=True))
        self._shown = {int(t) for t in p.track_ids}

    @staticmethod
    def _log_skeletons(rec: rr.RecordingStream, base: str, ids: np.ndarray, points: np.ndarray,
                       confidences: np.ndarray, kind: type[rr.Points2D] | type[rr.Points3D]) -> None:
        """One entity per person (so that the keypoint connections stay within a person).

        ``ids`` (N,) track ids; ``points`` (N, 17, 2) pixels or (N, 17, 3) world frame, metres (``kind``
        says which); ``confidences`` (N, 17), 0 where a keypoint is not seen.
        """
        for tid, pts, conf in zip(ids, points, confidences):
            seen = np.flatnonzero(conf > 0)
            radius = 0.05 if kind is rr.Points3D else 2.0  # metres in 3D, pixels in the image
            # no keypoint names on screen: 17 labels per person hide the scene (the ids are on the boxes)
            rec.log(f"{base}/{int(tid)}", kind(pts[seen], keypoint_ids=seen, class_ids=PERSON_CLASS, radii=radius,
                                               show_labels=False))

    @staticmethod
    def _log_ground_truth(rec: rr.RecordingStream, frame: Frame) -> None:
        gt = frame.ground_truth
        if gt is None:  # an unlabelled frame (nuScenes sweeps): no stale truth from the last keyframe
            rec.log("world/ground_truth", rr.Clear(recursive=True))
            rec.log("world/ego/camera/image/ground_truth", rr.Clear(recursive=True))
            return
        labels = [f"gt {i}" for i in gt.ids]
        rec.log("world/ground_truth/positions", rr.Points3D(gt.positions, labels=labels, radii=0.2, colors=[_TRUTH]))
        rec.log("world/ego/camera/image/ground_truth", rr.Boxes2D(array=gt.boxes, array_format=rr.Box2DFormat.XYXY,
                                                                  colors=[_TRUTH]))
