"""Ego-motion compensation in the image (paper Eq. 1).

The paper writes ``u_comp = u - (dpsi / alpha) * w`` with CARLA's yaw, which turns
clockwise. In pedenv's right-handed world the yaw turns counter-clockwise: when the
ego turns left (``dpsi > 0``) the scene moves right in the image, so the tracks'
stored pixels move right by ``+ dpsi / alpha * w``.
"""

from __future__ import annotations

import numpy as np

from pedenv.geometry import wrap_angle


def yaw_change(previous_yaw: float, yaw: float) -> float:
    """Yaw change in radians from ``previous_yaw`` to ``yaw``, wrapped to [-pi, pi)."""
    return float(wrap_angle(yaw - previous_yaw))


def yaw_shift_pixels(delta_yaw: float, hfov: float, width: int) -> float:
    """Horizontal pixel shift of the scene for a yaw change (Eq. 1, right-handed sign).

    delta_yaw: radians, counter-clockwise positive. hfov: horizontal field of view,
    radians. width: image width in pixels. Returns pixels, positive = to the right.
    """
    return float(delta_yaw) / float(hfov) * float(width)


def shift_u(points: np.ndarray, shift: float) -> np.ndarray:
    """Copy of ``points`` (..., 2k) pixels with every u coordinate moved by ``shift``.

    Works on keypoints (..., 2) and on boxes (..., 4) ``[u_min, v_min, u_max, v_max]``.
    """
    out = np.array(points, dtype=np.float64, copy=True)
    out[..., 0::2] += shift
    return out
