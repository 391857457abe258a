"""Test helpers: a simple standing person and frames whose detections are its exact projections."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from pedenv.body import standing_body, world_keypoints
from pedenv.geometry import invert_transform, project
from pedenv.records import Camera, Detections, EgoPose, Frame


def person_points(xy, height: float = 1.72, ground_z: float = 0.0) -> np.ndarray:
    """(17, 3) world keypoints of a person of the body template standing at ``xy`` facing -x."""
    ground = np.array([[xy[0], xy[1], ground_z]], float)
    return world_keypoints(ground, np.array([np.pi]), standing_body([height]))[0]


def frame_with_people(index: int, t: float, ego: EgoPose, people_xy, camera: Camera | None = None,
                      height: float = 1.72) -> Frame:
    """A frame whose detections are the exact projections of standing people."""
    camera = camera or Camera.from_fov()
    frame = Frame(index, t, camera, ego)
    pts = np.stack([person_points(p, height) for p in people_xy]) if len(people_xy) else np.zeros((0, 17, 3))
    uv, _ = project(pts, camera.intrinsics, invert_transform(frame.cam_to_world))
    return replace(frame, detections=Detections(uv.reshape(-1, 17, 2), np.ones((len(people_xy), 17))))


