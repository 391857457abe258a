"""The ego's path so far, in pieces: what the Rerun and MCAP writers log per frame.

Logging the whole path every frame makes a file grow with the square of the stream's length
(72 MB of ``.rrd`` for 2,000 frames, 25 GB per hour at 30 Hz). The path is cut into pieces of
at most :data:`PIECE_POINTS` positions, each its own entity: a frame re-logs only the piece
being drawn, the finished pieces stay on screen, and the file grows linearly.
"""

from __future__ import annotations

import numpy as np

#: Positions per piece of the ego's path (consecutive pieces share their end point).
PIECE_POINTS = 100


class EgoPath:
    """The ego positions of one scene. ``add(position)`` -> (piece number, (K, 3) its points)."""

    def __init__(self, piece_points: int = PIECE_POINTS) -> None:
        if not 2 <= int(piece_points) <= 100_000:
            raise ValueError(f"piece_points must be in [2, 100000], got {piece_points}")
        self.piece_points = int(piece_points)
        self.piece = 0
        self._points: list[np.ndarray] = []

    def add(self, position: np.ndarray) -> tuple[int, np.ndarray]:
        """Append ``position`` ((3,) world frame, metres); the piece it is in and that piece's points."""
        if len(self._points) >= self.piece_points:
            self.piece += 1
            self._points = self._points[-1:]  # the new piece starts where the last one ended
        self._points.append(np.asarray(position, float))
        return self.piece, np.array(self._points)
