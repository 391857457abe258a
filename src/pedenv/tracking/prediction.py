"""Where each track's box will be in the next frame: the one prediction the tracker gates with
and the detector searches at (:meth:`pedenv.model.PedestrianEnvironmentModel.predict_tracks`)."""

from __future__ import annotations

import numpy as np

from pedenv.tracking.egomotion import shift_u


def predict_boxes(boxes: np.ndarray, velocities: np.ndarray, u_shift: float, motion: bool) -> np.ndarray:
    """The tracks' ``boxes`` (T, 4) px of the last frame moved into the next one: by the ego-yaw
    shift ``u_shift`` px along u (paper Eq. 1; 0 when it is off or the camera is static), then,
    with ``motion`` (``tracking.predict_motion``), by their image ``velocities`` (T, 4) px per
    frame (constant velocity in the image). Returns a new (T, 4) array."""
    moved = shift_u(boxes, u_shift) if u_shift else np.array(boxes, np.float64, copy=True)
    return moved + velocities if motion else moved
