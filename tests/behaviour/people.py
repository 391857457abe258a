"""Constructed people for the behaviour tests: exact COCO-17 skeletons seen by the paper's camera."""

from __future__ import annotations

import numpy as np

from pedenv.body import world_keypoints
from pedenv.geometry import invert_transform, pixel_rays, project
from pedenv.records import Camera, EgoPose
from pedenv.synthetic.walker import body_keypoints

CAMERA = Camera.from_fov(1600, 900, 64.5, height_m=1.5)
EGO = EgoPose.from_xy_yaw(0.0, 0.0, 0.0)  # looking along world +x


def seen(ground_xy, heading, height=1.72, walking=True):
    """Rays (N, 17, 3), confidences (N, 17), positions (N, 3), origin (3,), focal (px) of people at
    ground_xy (N, 2) world metres facing ``heading`` (N,) radians, as the camera sees them."""
    ground_xy = np.atleast_2d(np.asarray(ground_xy, float))
    n = len(ground_xy)
    heading = np.broadcast_to(np.asarray(heading, float), (n,))
    body = body_keypoints(np.full(n, height), np.zeros(n), np.full(n, 1.0 if walking else 0.0), np.zeros((n, 2)))
    feet = np.column_stack([ground_xy, np.zeros(n)])
    cam_to_world = EGO.matrix @ CAMERA.cam_to_vehicle
    uv, _ = project(world_keypoints(feet, heading, body), CAMERA.intrinsics, invert_transform(cam_to_world))
    rays = pixel_rays(uv, CAMERA.intrinsics, cam_to_world)
    return rays, np.full((n, 17), 0.9), feet, cam_to_world[:3, 3], float(CAMERA.intrinsics[0, 0])
