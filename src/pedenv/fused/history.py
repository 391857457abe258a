"""Each track's past observations, row-aligned with the tracker's table.

Slot 0 is the newest observation; a push shifts a track's slots back by one, so the
table is a fixed-size ring per track and a frame costs a few array copies.
"""

from __future__ import annotations

import numpy as np

from pedenv.skeleton import CocoKeypoint as K
from pedenv.tracker import carry_rows

#: The keypoints triangulated over the history: shoulders and hips, the steadiest points
#: of a walking body (arms and legs swing, the head turns).
TORSO_KEYPOINTS = np.array([K.LEFT_SHOULDER, K.RIGHT_SHOULDER, K.LEFT_HIP, K.RIGHT_HIP])


class TrackHistory:
    """Past rays of every track.

    rays: (T, L, 4, 3) unit, world, of the torso keypoints. usable: (T, L, 4) bool.
    origins: (T, L, 3) camera centres, world, metres. times: (T, L) seconds.
    filled: (T, L) bool, slot holds an observation.
    positions: (T, 2) the last fused ground point, world x-y, metres. placed: (T,) bool,
    ``positions`` holds one (a cue placed the track before).
    """

    def __init__(self, length: int) -> None:
        self.length = int(length)
        self.reset()

    def reset(self) -> None:
        L, k = self.length, len(TORSO_KEYPOINTS)
        self.rays = np.zeros((0, L, k, 3))
        self.usable = np.zeros((0, L, k), bool)
        self.origins = np.zeros((0, L, 3))
        self.times = np.zeros((0, L))
        self.filled = np.zeros((0, L), bool)
        self.positions = np.zeros((0, 2))
        self.placed = np.zeros(0, bool)

    def carry(self, previous_rows: np.ndarray) -> None:
        """Follow the tracker's new table (see :func:`pedenv.tracker.carry_rows`)."""
        for name in ("rays", "usable", "origins", "times", "filled", "positions", "placed"):
            setattr(self, name, carry_rows(getattr(self, name), previous_rows))

    def push(self, rows: np.ndarray, rays: np.ndarray, usable: np.ndarray, origin: np.ndarray, time: float) -> None:
        """Add this frame's observation of the tracks at ``rows`` (N,), unique.

        rays: (N, 4, 3) unit, world; usable: (N, 4) bool; origin: (3,) world; time: seconds.
        """
        for name, new in (("rays", rays), ("usable", usable), ("origins", np.broadcast_to(origin, (len(rows), 3))),
                          ("times", np.full(len(rows), time)), ("filled", np.ones(len(rows), bool))):
            table = getattr(self, name)
            table[rows, 1:] = table[rows, :-1]
            table[rows, 0] = new

    def place(self, rows: np.ndarray, positions: np.ndarray, valid: np.ndarray) -> None:
        """Remember the fused ground points (N, 2) world x-y of the tracks at ``rows`` where ``valid`` (N,)."""
        self.positions[rows[valid]] = positions[valid]
        self.placed[rows[valid]] = True
