"""The closed-form start of the fit: horizon, vertical vanishing point, focal length, tilt, height.

On flat ground a person's pixel span grows linearly with the row of the feet and is zero on
the horizon (exact for a level camera, close for a tilted one); the feet-to-head lines meet in
the vertical vanishing point ``V``. With the principal point ``c``, the horizon's distance
``d_h`` above ``c`` and ``V``'s distance ``d_v`` below it give ``f^2 = d_h d_v`` and
``tan(tilt) = d_h / f`` (the orthocentre relation of the vanishing points, square pixels).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.calibration.observations import Observations


@dataclass(frozen=True)
class Start:
    """The closed-form estimate: horizon row and slope (span px per row of the feet), vertical
    vanishing point row (pixels, ``inf`` when the feet-to-head lines are parallel), focal
    length (pixels, None when the lines are too close to parallel to give it), tilt (rad),
    height (m)."""

    horizon_v: float
    span_per_row: float
    vanishing_v: float
    focal: float | None
    tilt: float
    height: float


def span_line(obs: Observations) -> tuple[float, float]:
    """(slope, horizon row): the people's pixel span against their feet's row, fitted by least
    squares after dropping the worst tenth (sitting or cut-off people the filter let through)."""
    v, span = obs.feet[:, 1], obs.feet[:, 1] - obs.heads[:, 1]
    keep = np.ones(len(v), bool)
    for _ in range(2):
        a, b = np.polyfit(v[keep], span[keep], 1)
        miss = np.abs(span - (a * v + b))
        keep = miss <= np.quantile(miss, 0.9) + 1e-9
    a, b = np.polyfit(v[keep], span[keep], 1)
    return float(a), float(-b / a) if a > 0 else float("nan")


def vanishing_row(obs: Observations) -> float:
    """Row (pixels) where the feet-to-head lines meet, least squares over the normalized lines;
    ``inf`` (or a negative-side row) when they are parallel or converge upwards."""
    ones = np.ones((len(obs), 1))
    lines = np.cross(np.hstack([obs.feet, ones]), np.hstack([obs.heads, ones]))
    lines /= np.hypot(lines[:, 0], lines[:, 1])[:, None]
    scale = float(np.abs(obs.feet).max())
    lines[:, 2] /= scale  # condition the solve: pixels in units of the image's size
    point = np.linalg.svd(lines)[2][-1]
    if abs(point[2]) < 1e-12:
        return float("inf")
    return float(point[1] / point[2] * scale)


def closed_form(obs: Observations, centre: tuple[float, float], span_world_m: float, ankle_m: float,
                focal: float | None = None) -> Start:
    """The start from ``obs``: ``span_world_m`` the mean ankle-to-head height (m) and
    ``ankle_m`` the ankle keypoint's height above the ground (m); ``focal`` (pixels) when known."""
    slope, horizon = span_line(obs)
    vanish = vanishing_row(obs)
    d_h, d_v = centre[1] - horizon, vanish - centre[1]
    f = focal
    if f is None and np.isfinite(d_h * d_v) and d_h * d_v > 0:
        f = float(np.sqrt(d_h * d_v))
    tilt = float(np.arctan2(d_h, f)) if f is not None and np.isfinite(d_h) else 0.0
    height = ankle_m + span_world_m / slope if slope > 0 else float("nan")
    return Start(horizon, slope, vanish, f, tilt, height)
