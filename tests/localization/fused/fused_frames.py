"""Hand-built frames for the fused cues: upright people at known ground points, seen by a
camera on a (possibly pitched) vehicle."""

from __future__ import annotations

import numpy as np

from pedenv.body import standing_body, world_keypoints
from pedenv.geometry import invert_transform, project, rotation_from_ypr
from pedenv.records import Camera, Detections, EgoPose, Frame


def upright_skeletons(ground: np.ndarray, heights: np.ndarray) -> np.ndarray:
    """(N, 17, 3) world keypoints of upright people (the body template) standing on ``ground`` (N, 3), facing +x."""
    ground = np.asarray(ground, float)
    return world_keypoints(ground, np.zeros(len(ground)), standing_body(heights))


def make_frame(ground: np.ndarray, heights=None, *, pitch: float = 0.0, roll: float = 0.0, yaw: float = 0.0,
               ego_xyz=(0.0, 0.0, 0.0), index: int = 0, timestamp: float = 0.0, hidden=()) -> Frame:
    """A frame with exact detections of upright people at ``ground`` (N, 3) world points.

    ``hidden``: keypoint indices given confidence 0 for everyone.
    """
    ground = np.asarray(ground, float).reshape(-1, 3)
    heights = np.full(len(ground), 1.72) if heights is None else np.asarray(heights, float)
    camera = Camera.from_fov(1600, 900, 64.5, height_m=1.5)
    ego = EgoPose(np.asarray(ego_xyz, float), rotation_from_ypr(yaw, pitch, roll))
    frame = Frame(index, timestamp, camera, ego)
    px, depth = project(upright_skeletons(ground, heights), camera.intrinsics, invert_transform(frame.cam_to_world))
    conf = (depth > 0).astype(float)
    conf[:, list(hidden)] = 0.0
    return Frame(index, timestamp, camera, ego, detections=Detections(px, conf))



def skeletons_of(frame: Frame, config=None, noise_px: float | None = None):
    """The frame's :class:`~pedenv.localization.fused.cue.FrameSkeletons` as the locator builds them;
    ``noise_px`` sets every skeleton's keypoint noise (else observed from the skeleton)."""
    from dataclasses import replace

    from pedenv.config import FusedConfig
    from pedenv.geometry import pixel_rays
    from pedenv.localization.fused.cue import FrameSkeletons, keypoint_usable

    config = config or FusedConfig()
    det, focal = frame.detections, float(frame.camera.intrinsics[0, 0])
    rays = pixel_rays(det.keypoints, frame.camera.intrinsics, frame.cam_to_world)
    usable = keypoint_usable(det.keypoints, det.confidences, frame.camera.width, frame.camera.height)
    skel = FrameSkeletons.of(rays, frame.cam_to_world[:3, 3], usable, config.keypoint_pixel_std / focal)
    return skel if noise_px is None else replace(skel, noise=np.full(len(rays), noise_px / focal))
