"""Small hand-built scenes for the dataset adapters and writers.

Pedestrians are a standing COCO-17 template skeleton placed in the world; their 2D skeletons
are the exact projections through the frame's camera, so writers and readers can be checked
to 1e-6.
"""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.body import standing_body
from pedenv.geometry import invert_transform, project, rotation_from_ypr, rotation_z
from pedenv.records import Camera, EgoPose, Frame, GroundTruth, Scene, boxes_from_keypoints

#: The body template's COCO-17 person 1.75 m tall, in its body frame (facing +x, left = +y), metres.
TEMPLATE = standing_body([1.75])[0]

#: Pedestrians: id, start (x, y) in the world, velocity (vx, vy) m/s.
PEDESTRIANS = (
    (3, (12.0, 2.0), (0.0, -1.2)),
    (7, (20.0, -4.0), (0.5, 0.8)),
    (11, (8.0, -3.5), (1.0, 0.0)),
    (42, (35.0, 6.0), (-0.8, -0.4)),
)


def frame_at(index: int, t: float, camera: Camera, *, ego_speed: float = 3.0, yaw_rate: float = 0.05,
             pitch: float = 0.01, scene: str = "") -> Frame:
    """The frame at ``t`` seconds: the ego drives and turns; ground truth of the pedestrians in view."""
    yaw = yaw_rate * t
    ego = EgoPose(np.array([ego_speed * t, 0.3 * t * t, 0.02 * t]), rotation_from_ypr(yaw, pitch * np.sin(t), 0.005))
    frame = Frame(index=index, timestamp=t, camera=camera, ego=ego, scene=scene)
    world_to_cam = invert_transform(frame.cam_to_world)
    ids, pos, kp, kp3, vis = [], [], [], [], []
    for pid, (x0, y0), (vx, vy) in PEDESTRIANS:
        p = np.array([x0 + vx * t, y0 + vy * t, 0.0])
        heading = np.arctan2(vy, vx)
        k3 = TEMPLATE @ rotation_z(heading).T + p
        uv, depth = project(k3, camera.intrinsics, world_to_cam)
        inside = (
            (depth > 0.5)
            & (uv[:, 0] > 0)
            & (uv[:, 0] < camera.width - 1)
            & (uv[:, 1] > 0)
            & (uv[:, 1] < camera.height - 1)
        )
        if inside.sum() < 3:
            continue
        ids.append(pid), pos.append(p), kp.append(uv), kp3.append(k3), vis.append(inside)
    if ids:
        kp_a, vis_a = np.array(kp), np.array(vis)
        truth = GroundTruth(np.array(ids), np.array(pos), boxes_from_keypoints(kp_a, vis_a), kp_a, vis_a,
                            np.full(len(ids), 1.75), np.array(kp3))
    else:
        truth = GroundTruth.empty()
    return Frame(index=index, timestamp=t, camera=camera, ego=ego, ground_truth=truth, scene=scene)


def make_scene(name: str = "scene-0001", n_frames: int = 13, rate_hz: float = 12.0, t0: float = 0.0, **kwargs) -> Scene:
    camera = Camera.from_fov(1600, 900, 64.5, height_m=1.5, forward_m=1.7)
    return Scene(name, tuple(frame_at(i, t0 + i / rate_hz, camera, scene=name, **kwargs) for i in range(n_frames)))


@pytest.fixture(scope="session")
def scene_factory():
    """``scene_factory(name, n_frames, rate_hz, t0)`` -> a small hand-built :class:`Scene`."""
    return make_scene
