"""Test helpers: a simple standing person and frames whose detections are its exact projections."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from pedenv.geometry import invert_transform, project
from pedenv.records import Camera, Detections, EgoPose, Frame

#: A standing COCO-17 person 1 m tall (fractions of the height), facing the camera.
HEIGHT_FRACTION = np.array([.92, .94, .94, .93, .93, .82, .82, .62, .62, .48, .48, .53, .53, .29, .29, .05, .05])
LATERAL = np.array([0, .03, -.03, .07, -.07, .2, -.2, .24, -.24, .25, -.25, .1, -.1, .1, -.1, .1, -.1])


def person_points(xy, height: float = 1.72, ground_z: float = 0.0) -> np.ndarray:
    """(17, 3) world keypoints of a person standing at ``xy`` facing -x."""
    return np.column_stack([np.full(17, xy[0]), xy[1] + LATERAL * height, ground_z + HEIGHT_FRACTION * height])


def frame_with_people(index: int, t: float, ego: EgoPose, people_xy, camera: Camera | None = None,
                      height: float = 1.72) -> Frame:
    """A frame whose detections are the exact projections of standing people."""
    camera = camera or Camera.from_fov()
    frame = Frame(index, t, camera, ego)
    pts = np.stack([person_points(p, height) for p in people_xy]) if len(people_xy) else np.zeros((0, 17, 3))
    uv, _ = project(pts, camera.intrinsics, invert_transform(frame.cam_to_world))
    return replace(frame, detections=Detections(uv.reshape(-1, 17, 2), np.ones((len(people_xy), 17))))


