"""A picture of an estimate: the horizon, a ground grid and the fitted people drawn on a frame."""

from __future__ import annotations

import cv2
import numpy as np

from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.geometry import camera_rotation, horizon_line, intrinsics, project
from pedenv.calibration.observations import Observations

#: Ground grid drawn: lines every this many metres, out to this range and this far to each side.
GRID_STEP_M, GRID_RANGE_M, GRID_SIDE_M = 5.0, 60.0, 30.0
_HORIZON, _GRID, _SEEN, _FITTED = (255, 60, 60), (60, 200, 255), (255, 255, 0), (40, 255, 40)


def draw_calibration(image: np.ndarray, estimate: CameraEstimate, people: Observations,
                     heads: np.ndarray | None = None) -> np.ndarray:
    """``image`` (H, W, 3) uint8 RGB with the horizon, a ground grid (metres on the ground under
    the camera) and ``people`` (their feet-to-head lines as seen, and ``heads`` (N, 2) px, where the
    fit puts their heads); returns a drawn copy."""
    out = np.ascontiguousarray(image.copy())
    k, r = intrinsics(estimate.focal, estimate.centre), camera_rotation(estimate.tilt, estimate.roll)
    a, b, c = horizon_line(k, r)
    width = out.shape[1]
    if abs(b) > 1e-9:
        cv2.line(out, (0, int(round(-c / b))), (width - 1, int(round(-(c + a * (width - 1)) / b))), _HORIZON, 2)
    for x in np.arange(GRID_STEP_M, GRID_RANGE_M + 1e-9, GRID_STEP_M):
        _polyline(out, np.c_[np.full(61, x), np.linspace(-GRID_SIDE_M, GRID_SIDE_M, 61), np.zeros(61)], k, r, estimate)
    for y in np.arange(-GRID_SIDE_M, GRID_SIDE_M + 1e-9, GRID_STEP_M):
        _polyline(out, np.c_[np.linspace(1.0, GRID_RANGE_M, 60), np.full(60, y), np.zeros(60)], k, r, estimate)
    for i in range(len(people)):
        foot, head = people.feet[i], people.heads[i]
        cv2.line(out, _pt(foot), _pt(head), _SEEN, 1)
        if heads is not None and np.isfinite(heads[i]).all():
            cv2.circle(out, _pt(heads[i]), 4, _FITTED, 2)
    text = (f"f {estimate.focal:.0f} px  height {estimate.height:.2f} m  tilt {np.degrees(estimate.tilt):.1f} deg  "
            f"roll {np.degrees(estimate.roll):.1f} deg  ({estimate.people} people)")
    cv2.putText(out, text, (10, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (0, 0, 0), 4, cv2.LINE_AA)
    cv2.putText(out, text, (10, 24), cv2.FONT_HERSHEY_SIMPLEX, 0.6, (255, 255, 255), 1, cv2.LINE_AA)
    return out


def _pt(p: np.ndarray) -> tuple[int, int]:
    return int(round(float(p[0]))), int(round(float(p[1])))


def _polyline(out: np.ndarray, points: np.ndarray, k: np.ndarray, r: np.ndarray, estimate: CameraEstimate) -> None:
    uv = project(points, k, r, estimate.height)
    ok = np.isfinite(uv).all(axis=1) & (np.abs(uv) < 1e5).all(axis=1)
    if ok.sum() >= 2:
        cv2.polylines(out, [np.round(uv[ok]).astype(np.int32)], False, _GRID, 1, cv2.LINE_AA)
