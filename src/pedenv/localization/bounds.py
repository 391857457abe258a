"""What may leave a position method: finite values within the method's maximum range.

Every locator's :class:`~pedenv.localization.base.Measurement` passes through
:func:`bound_measurement` in the model before it reaches the Kalman filter, and the
filtered positions pass through :func:`clamp_to_range` before they reach the output:

* a row with any NaN or inf (position, covariance, skeleton) is *unlocalised*: it is no
  measurement for the filter, its source is ``unlocalised``, and it is placed at the
  maximum range along its box centre's bearing with a covariance of ``max_range_m**2``
  per axis (its range is unknown);
* a position farther than the maximum range (horizontally from the camera) is *clamped*
  to it along its own bearing, its covariance along the ray widened by
  ``max_range_m**2`` and ``;clamped`` appended to its source.

So no NaN, no inf and no position beyond the cap is ever reported.
"""

from __future__ import annotations

import numpy as np

from pedenv.localization.base import Measurement

UNLOCALISED = "unlocalised"
CLAMPED = ";clamped"


def finite_rows(*arrays: np.ndarray | None) -> np.ndarray:
    """(N,) bool: rows where every value of every (N, ...) array is finite (None is skipped)."""
    present = [a for a in arrays if a is not None]
    ok = np.ones(len(present[0]), bool)
    for a in present:
        ok &= np.isfinite(a.reshape(len(a), -1)).all(axis=1)
    return ok


def bearings(xy: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal ranges (N,) and unit bearings (N, 2) of world points ``xy`` (N, 2) from
    ``origin`` (3,), metres; overflow-safe (``np.hypot``); a point at the origin gets +x."""
    offset = xy - origin[:2]
    ranges = np.hypot(offset[:, 0], offset[:, 1])
    safe = np.where(ranges > 0, ranges, 1.0)
    unit = np.where((ranges > 0)[:, None], offset / safe[:, None], [1.0, 0.0])
    return ranges, unit


def along_ray(bearing: np.ndarray, variance: float) -> np.ndarray:
    """(N, 2, 2) covariance ``variance * b b^T`` along the bearings ``b`` (N, 2), m^2."""
    return variance * bearing[:, :, None] * bearing[:, None, :]


def clamp_to_range(
    positions: np.ndarray, origin: np.ndarray, max_range_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (N, 3) world, metres, moved in x-y onto the circle of ``max_range_m``
    around the camera ``origin`` (3,) where they lie beyond it.

    Returns ``(positions, clamped (N,) bool, bearings (N, 2))``.
    """
    ranges, unit = bearings(positions[:, :2], origin)
    clamped = ranges > max_range_m
    out = positions.copy()
    out[clamped, :2] = origin[:2] + max_range_m * unit[clamped]
    return out, clamped, unit


def clamp_reported(positions: np.ndarray, covariances: np.ndarray, skeletons: np.ndarray, sources: np.ndarray,
                   origin: np.ndarray, max_range_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What the model reports, held to the range like a measurement (the filter may drift beyond).

    positions (N, 3), covariances (N, 2, 2), skeletons (N, 17, 3), sources (N,) str; world,
    metres. A row beyond ``max_range_m`` from the camera ``origin`` (3,) moves onto that
    circle with its skeleton, its covariance widened along the ray by ``max_range_m**2``
    and ``;clamped`` added to its source. Returns the four, changed where clamped.
    """
    out, clamped, unit = clamp_to_range(positions, origin, max_range_m)
    if clamped.any():
        skeletons = skeletons.copy()
        skeletons[clamped] += (out[clamped] - positions[clamped])[:, None, :]
        covariances = covariances.copy()
        covariances[clamped] += along_ray(unit[clamped], max_range_m**2)
        sources = np.where(clamped & ~np.char.endswith(sources, CLAMPED), np.char.add(sources, CLAMPED), sources)
    return out, covariances, skeletons, sources


def unlocalised_positions(centre_rays: np.ndarray, origin: np.ndarray, ground_z: float,
                          max_range_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Where an unlocalised detection is reported: ``max_range_m`` along the horizontal
    bearing of its box centre's ray ``centre_rays`` (N, 3), on the road (``ground_z``),
    with covariance ``max_range_m**2`` per axis. Returns ``(positions (N, 3), covariances (N, 2, 2))``."""
    _, unit = bearings(origin[:2] + np.nan_to_num(centre_rays[:, :2]), origin)
    positions = np.column_stack([origin[:2] + max_range_m * unit, np.full(len(unit), ground_z)])
    return positions, np.broadcast_to(max_range_m**2 * np.eye(2), (len(unit), 2, 2)).copy()


def bound_measurement(meas: Measurement, centre_rays: np.ndarray, origin: np.ndarray, ground_z: float,
                      max_range_m: float) -> tuple[Measurement, np.ndarray]:
    """The measurement made finite and within ``max_range_m``, and which rows (N,) bool are
    real measurements for the filter (the finite ones; clamped rows count, widened).

    centre_rays: (N, 3) unit rays of the box centres, world. origin: (3,) camera centre,
    world, metres. ground_z: world z of the road under the ego, metres.
    """
    measured = finite_rows(meas.positions, meas.covariances, meas.bias_covariances, meas.keypoints_3d)
    positions, cov = meas.positions.copy(), meas.covariances.copy()
    bias = None if meas.bias_covariances is None else meas.bias_covariances.copy()
    skeleton = meas.keypoints_3d.copy()
    sources = np.asarray(meas.sources).astype(str)
    lost = ~measured
    if lost.any():
        positions[lost], cov[lost] = unlocalised_positions(centre_rays[lost], origin, ground_z, max_range_m)
        skeleton[lost] = positions[lost][:, None, :]
        if bias is not None:
            bias[lost] = 0.0
        sources = np.where(lost, UNLOCALISED, sources)
    clamped_pos, clamped, unit = clamp_to_range(positions, origin, max_range_m)
    clamped &= measured
    if clamped.any():
        skeleton[clamped] += (clamped_pos[clamped] - positions[clamped])[:, None, :]
        positions[clamped] = clamped_pos[clamped]
        cov[clamped] += along_ray(unit[clamped], max_range_m**2)
        sources = np.where(clamped, np.char.add(sources, CLAMPED), sources)
    return Measurement(positions, cov, sources, skeleton, bias), measured
