"""A rendered road scene with exact truth: a textured road (z = 0) between two textured walls,
seen by a camera 1.65 m up that drives forward and turns (vehicle frame x forward, y left, z up)."""

from __future__ import annotations

import cv2
import numpy as np

WIDTH, HEIGHT, FOCAL = 640, 360, 480.0
K = np.array([[FOCAL, 0.0, WIDTH / 2], [0.0, FOCAL, HEIGHT / 2], [0.0, 0.0, 1.0]])
CAMERA_HEIGHT_M = 1.65
#: Optical camera axes -> vehicle axes, looking straight ahead.
FORWARD = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
WALL_Y_M = 7.0  # walls at y = +-7 m (off the road plane: the essential matrix needs depth)
TEXEL_M = 0.08


def cam_to_vehicle(pitch_down_deg: float = 3.0) -> np.ndarray:
    """(4, 4) camera -> vehicle: 1.65 m over the road origin, pitched down by ``pitch_down_deg``."""
    p = np.radians(pitch_down_deg)
    pitch = np.array([[np.cos(p), 0.0, np.sin(p)], [0.0, 1.0, 0.0], [-np.sin(p), 0.0, np.cos(p)]])
    t = np.eye(4)
    t[:3, :3] = pitch @ FORWARD
    t[2, 3] = CAMERA_HEIGHT_M
    return t


def texture(seed: int = 0, size: int = 1024) -> np.ndarray:
    """(size, size) float32 grey texture, 0-255: blurred noise at two scales (corners for FAST)."""
    rng = np.random.default_rng(seed)
    fine = cv2.GaussianBlur(rng.random((size, size)).astype(np.float32), (0, 0), 1.2)
    coarse = cv2.resize(rng.random((size // 16, size // 16)).astype(np.float32), (size, size))
    tex = fine - fine.mean() + 0.5 * (coarse - coarse.mean())
    return np.clip(128 + tex * (90 / tex.std()), 0, 255).astype(np.float32)


def vehicle_pose(x: float, y: float, yaw_deg: float) -> np.ndarray:
    """(4, 4) vehicle -> world at (x, y) metres on the road heading ``yaw_deg``."""
    a = np.radians(yaw_deg)
    t = np.eye(4)
    t[:2, :2] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    t[:2, 3] = x, y
    return t


def render(tex: np.ndarray, ego: np.ndarray, mount: np.ndarray, still: bool = False) -> np.ndarray:
    """(HEIGHT, WIDTH) uint8 image of the scene from the camera ``mount`` on the vehicle at ``ego``
    (``still``: nothing but the road and walls, as here always; the flag keeps call sites readable)."""
    del still
    cam_to_world = ego @ mount
    v, u = np.mgrid[0:HEIGHT, 0:WIDTH].astype(np.float64)
    rays = cam_to_world[:3, :3] @ (np.linalg.inv(K) @ np.stack([u.ravel(), v.ravel(), np.ones(u.size)]))
    origin = cam_to_world[:3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.stack([np.where(rays[2] < 0, -origin[2] / rays[2], np.inf),
                          np.where(rays[1] > 0, (WALL_Y_M - origin[1]) / rays[1], np.inf),
                          np.where(rays[1] < 0, (-WALL_Y_M - origin[1]) / rays[1], np.inf)])
    which = np.argmin(reach, axis=0)
    dist = reach[which, np.arange(u.size)]
    hit = origin[:, None] + rays * np.where(np.isfinite(dist), dist, 0.0)
    # texture coordinates: the road's (x, y), a wall's (x, z) shifted so that the surfaces differ
    s = np.where(which == 0, hit[0], hit[0] + 37.0)
    t = np.where(which == 0, hit[1], hit[2] + 11.0 * which)
    size = tex.shape[0]
    map_x = np.mod(s / TEXEL_M, size).astype(np.float32).reshape(HEIGHT, WIDTH)
    map_y = np.mod(t / TEXEL_M, size).astype(np.float32).reshape(HEIGHT, WIDTH)
    image = cv2.remap(tex, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
    image[(~np.isfinite(dist) | (dist > 120.0)).reshape(HEIGHT, WIDTH)] = 200.0  # sky and the far distance
    return np.clip(image, 0, 255).astype(np.uint8)
