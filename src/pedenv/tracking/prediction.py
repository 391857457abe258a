"""Where each track's box will be in the next frame: the one prediction the tracker gates with
and the detector searches at (:meth:`pedenv.model.PedestrianEnvironmentModel.predict_tracks`)."""

from __future__ import annotations

import numpy as np

from pedenv.tracking.egomotion import shift_u


def box_displacement(velocities: np.ndarray) -> np.ndarray:
    """The displacement (T, 4) px a box is moved by for its smoothed edge ``velocities`` (T, 4) px
    per frame: both u edges by the mean of their velocities (the box keeps its width), each v edge
    by its own (the height follows the range). A skeleton's box widens and narrows with the gait
    (arms and legs swing out by tens of pixels from one frame to the next on a near walker, KITTI
    0016): extrapolated edge by edge, that swing collapses or inverts the predicted box (u_min
    beyond u_max), which then overlaps the person's neighbour better than the person."""
    v = np.asarray(velocities, np.float64)
    du = 0.5 * (v[:, 0] + v[:, 2])
    return np.column_stack([du, v[:, 1], du, v[:, 3]])


def predict_boxes(boxes: np.ndarray, velocities: np.ndarray, u_shift: float, motion: bool) -> np.ndarray:
    """The tracks' ``boxes`` (T, 4) px of the last frame moved into the next one: by the ego-yaw
    shift ``u_shift`` px along u (paper Eq. 1; 0 when it is off or the camera is static), then,
    with ``motion`` (``tracking.predict_motion``), by their image ``velocities`` (T, 4) px per
    frame (constant velocity in the image, :func:`box_displacement`). Returns a new (T, 4) array."""
    moved = shift_u(boxes, u_shift) if u_shift else np.array(boxes, np.float64, copy=True)
    return moved + box_displacement(velocities) if motion else moved
