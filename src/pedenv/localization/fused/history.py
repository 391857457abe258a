"""Each track's past keypoint rays, row-aligned with the tracker's table.

Each track has a fixed-size ring of slots; a push overwrites the track's oldest slot (its
``count`` modulo the length), so a frame writes one slot per track and moves nothing. The
slots are unordered: everything that reads them sums over them. Each ray is
stored with its least-squares terms (:func:`ray_terms`), so triangulating over the
history is one weighted sum per frame, not a rebuild of every past ray's matrices.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.tracking.table import ColumnGroup

#: The keypoints whose triangulation places the person: shoulders and hips, the
#: steadiest points of a walking body (arms and legs swing, the head turns).
TORSO_KEYPOINTS = np.array([KP.LEFT_SHOULDER, KP.RIGHT_SHOULDER, KP.LEFT_HIP, KP.RIGHT_HIP])
#: The cues that measure a track's body height (they place a person without assuming it).
HEIGHT_CUES = ("ground", "triangulation")
#: Layout of a ray's least-squares terms: the upper triangle of ``I - d d^T`` (xx, xy,
#: xz, yy, yz, zz) then ``(I - d d^T) o`` (3), d the ray, o the camera centre.
NUM_TERMS = 9
#: Per past camera: its centre (3), squared norm (1) and time (1).
CENTRE, CENTRE_SQ, TIME = slice(0, 3), 3, 4


def ray_terms(rays: np.ndarray, origin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares terms (..., 9) and ``d . o`` (...,) of unit rays d (..., 3), world,
    from ``origin`` o (3,), metres."""
    out = np.empty(rays.shape[:-1] + (NUM_TERMS,))
    dot = rays @ origin
    x, y, z = rays[..., 0], rays[..., 1], rays[..., 2]
    out[..., 0], out[..., 1], out[..., 2] = 1.0 - x * x, -x * y, -x * z
    out[..., 3], out[..., 4], out[..., 5] = 1.0 - y * y, -y * z, 1.0 - z * z
    out[..., 6:] = origin - rays * dot[..., None]
    return out, dot


@dataclass(frozen=True)
class HistoryView:
    """The past rays of N tracks, the slots of their rings side by side (L of them).

    rays: (N, 17, L, 3) unit, world. terms: (N, 17, L, 9) and dots: (N, 17, L) their
    least-squares terms (:func:`ray_terms`). usable: (N, 17, L) bool. cameras: (N, L, 5)
    each slot's camera: centre (world, metres), its squared norm, time (seconds).
    filled: (N, L) bool, the slot holds an observation.
    """

    rays: np.ndarray
    terms: np.ndarray
    dots: np.ndarray
    usable: np.ndarray
    cameras: np.ndarray
    filled: np.ndarray

    @property
    def centres(self) -> np.ndarray:
        """(N, L, 3) each slot's camera centre, world, metres."""
        return self.cameras[..., CENTRE]

    @property
    def centres_sq(self) -> np.ndarray:
        """(N, L) the squared norm of each slot's camera centre, m^2."""
        return self.cameras[..., CENTRE_SQ]

    @property
    def times(self) -> np.ndarray:
        """(N, L) each slot's time, seconds."""
        return self.cameras[..., TIME]


class TrackHistory(ColumnGroup):
    """Past rays of every track: the fused method's group of per-track columns.

    rays: (T, 17, L, 3) each keypoint's unit rays, world. terms: (T, 17, L, 9) and dots:
    (T, 17, L) their least-squares terms (:func:`ray_terms`). usable: (T, 17, L) bool.
    cameras: (T, L, 5) camera centre (world, metres), its squared norm and the time
    (seconds). filled: (T, L) bool, slot holds an observation. count: (T,) pushes so far.
    positions: (T, 2) the last fused ground point, world x-y, metres. placed: (T,) bool,
    ``positions`` holds one (a cue placed the track before). skeletons: (T, 17, 3) the
    last 3D skeleton, world, metres (valid where ``placed``). height_sums: (T, C, 3) the body
    height measured by each of :data:`HEIGHT_CUES` (C), as sums ``(sum w, sum w H, sum w s)``
    (:mod:`~pedenv.localization.fused.body_height`).
    """

    rays: np.ndarray
    terms: np.ndarray
    dots: np.ndarray
    usable: np.ndarray
    cameras: np.ndarray
    filled: np.ndarray
    positions: np.ndarray
    placed: np.ndarray
    skeletons: np.ndarray
    count: np.ndarray
    height_sums: np.ndarray

    def __init__(self, length: int) -> None:
        self.length = L = int(length)
        k, f = NUM_KEYPOINTS, np.float64
        super().__init__({
            "rays": ((k, L, 3), f), "terms": ((k, L, NUM_TERMS), f), "dots": ((k, L), f), "usable": ((k, L), bool),
            "cameras": ((L, 5), f), "filled": ((L,), bool), "positions": ((2,), f), "placed": ((), bool),
            "skeletons": ((k, 3), f), "count": ((), np.int64), "height_sums": ((len(HEIGHT_CUES), 3), f)})

    def push(self, rows: np.ndarray, rays: np.ndarray, terms: np.ndarray, dots: np.ndarray, usable: np.ndarray,
             origin: np.ndarray, time: float) -> None:
        """Add this frame's observation of the tracks at ``rows`` (N,), unique.

        rays: (N, 17, 3) unit, world; terms, dots: (N, 17, 9), (N, 17) (:func:`ray_terms`);
        usable: (N, 17) bool;
        origin: (3,) camera centre, world, metres; time: seconds.
        """
        slot = self.count[rows] % self.length
        self.rays[rows, :, slot] = rays
        self.terms[rows, :, slot] = terms
        self.dots[rows, :, slot] = dots
        self.usable[rows, :, slot] = usable
        self.cameras[rows, slot] = (*origin, float(origin @ origin), time)
        self.filled[rows, slot] = True
        self.count[rows] += 1

    def forget_before_gap(self, rows: np.ndarray, since: float) -> None:
        """Empty the rings of the tracks at ``rows`` (N,) whose newest observation is older
        than ``since`` (seconds): their past rays lie across a gap of missed frames."""
        filled = self.filled[rows]
        newest = np.where(filled, self.cameras[rows, :, TIME], -np.inf).max(axis=1)
        stale = rows[filled.any(axis=1) & (newest < since)]
        self.filled[stale] = False
        self.usable[stale] = False

    def of(self, rows: np.ndarray) -> HistoryView:
        """The histories of the tracks at ``rows`` (N,); views, not copies, when ``rows`` is
        the whole table in order (the usual case)."""
        if len(rows) == len(self.count) and (rows == np.arange(len(rows))).all():
            return HistoryView(self.rays, self.terms, self.dots, self.usable, self.cameras, self.filled)
        return HistoryView(self.rays[rows], self.terms[rows], self.dots[rows], self.usable[rows], self.cameras[rows],
                           self.filled[rows])

    def place(self, rows: np.ndarray, positions: np.ndarray, skeletons: np.ndarray, valid: np.ndarray) -> None:
        """Remember the fused ground points (N, 2) world x-y and 3D skeletons (N, 17, 3) of
        the tracks at ``rows`` where ``valid`` (N,)."""
        self.positions[rows[valid]] = positions[valid]
        self.skeletons[rows[valid]] = skeletons[valid]
        self.placed[rows[valid]] = True
