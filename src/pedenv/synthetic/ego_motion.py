"""The ego vehicle's motion: speed and yaw-rate profiles integrated to poses on the terrain.

The vehicle origin is on the road midway between the axles. On terrain its height is
the mean of the terrain under its four wheels, its pitch and roll follow the slope
between the axles and between the sides, and the suspension pitches the nose up when
accelerating and down when braking. On flat ground the vehicle never pitches or rolls.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import cast

import numpy as np

from pedenv.geometry import rotation_from_ypr
from pedenv.records import EgoPose
from pedenv.synthetic.terrain import Terrain

WHEELBASE_M = 2.8
TRACK_WIDTH_M = 1.6
#: Suspension pitch per longitudinal acceleration: 0.5 deg per m/s^2, nose up when accelerating.
SUSPENSION_PITCH_RAD_PER_MPS2 = np.radians(0.5)

Profile = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class EgoTrack:
    """The ego's planar motion sampled at the frame times.

    times: (T,) seconds. xy: (T, 2) world frame, metres. yaw: (T,) radians.
    speed: (T,) m/s. acceleration: (T,) m/s^2, longitudinal. yaw_rate: (T,) rad/s.
    """

    times: np.ndarray
    xy: np.ndarray
    yaw: np.ndarray
    speed: np.ndarray
    acceleration: np.ndarray
    yaw_rate: np.ndarray


def smooth_step(t: np.ndarray, start: float, duration: float) -> np.ndarray:
    """0 before ``start``, 1 after ``start + duration``, a cosine ramp between: (T,) -> (T,)."""
    x = np.clip((np.asarray(t, float) - start) / max(duration, 1e-9), 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * x)


def integrate_track(times: np.ndarray, speed: Profile, yaw_rate: Profile, *, start_xy: tuple[float, float] = (0.0, 0.0),
                    start_yaw: float = 0.0, rate_hz: float = 200.0) -> EgoTrack:
    """Integrate ``speed(t)`` (m/s) and ``yaw_rate(t)`` (rad/s) on a fine grid, sample at ``times``."""
    times = np.asarray(times, float)
    fine = np.linspace(0.0, times[-1], max(int(np.ceil(times[-1] * rate_hz)), 1) + 1)
    v, w = speed(fine), yaw_rate(fine)
    dt = np.diff(fine)
    yaw = start_yaw + np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * dt)])
    vx, vy = v * np.cos(yaw), v * np.sin(yaw)
    x = start_xy[0] + np.concatenate([[0.0], np.cumsum(0.5 * (vx[1:] + vx[:-1]) * dt)])
    y = start_xy[1] + np.concatenate([[0.0], np.cumsum(0.5 * (vy[1:] + vy[:-1]) * dt)])
    acc = np.gradient(v, fine) if fine.size > 1 else np.zeros_like(v)
    sample = lambda a: np.interp(times, fine, a)  # noqa: E731
    return EgoTrack(times, np.stack([sample(x), sample(y)], axis=1), sample(yaw), sample(v), sample(acc), sample(w))


def ego_poses(track: EgoTrack, terrain: Terrain) -> list[EgoPose]:
    """One :class:`EgoPose` per sample of ``track`` standing on ``terrain``.

    Flat terrain gives z = 0 and no pitch or roll (the suspension is ignored there too):
    the vehicle's z axis is exactly the world's.
    """
    if terrain.is_flat:
        return [EgoPose.from_xy_yaw(x, y, yaw) for (x, y), yaw in zip(track.xy, track.yaw)]
    c, s = np.cos(track.yaw), np.sin(track.yaw)
    fwd = np.stack([c, s], axis=1)
    left = np.stack([-s, c], axis=1)
    half_l, half_w = WHEELBASE_M / 2.0, TRACK_WIDTH_M / 2.0
    wheels = {(fx, sy): terrain.height(track.xy + fx * half_l * fwd + sy * half_w * left)
              for fx in (1, -1) for sy in (1, -1)}
    front = 0.5 * (wheels[1, 1] + wheels[1, -1])
    rear = 0.5 * (wheels[-1, 1] + wheels[-1, -1])
    left_z = 0.5 * (wheels[1, 1] + wheels[-1, 1])
    right_z = 0.5 * (wheels[1, -1] + wheels[-1, -1])
    z = cast(np.ndarray, 0.25 * sum(wheels.values()))  # (T,) metres
    # positive pitch turns the nose down (front lower); accelerating lifts it
    pitch = np.arctan2(rear - front, WHEELBASE_M) - SUSPENSION_PITCH_RAD_PER_MPS2 * track.acceleration
    roll = np.arctan2(left_z - right_z, TRACK_WIDTH_M)  # positive roll lifts the left side
    return [EgoPose(np.array([x, y, zz]), rotation_from_ypr(yaw, p, r))
            for (x, y), zz, yaw, p, r in zip(track.xy, z, track.yaw, pitch, roll)]
