"""The ``stream`` scheduler: which network passes a frame gets within its budget (pure functions).

Costs are network units (one 384x640 input). Every frame pays the whole-frame pass. A frame
may spend ``budget_units`` plus the ``credit`` banked by earlier frames that spent less
(:class:`CreditBank`; at most ``credit_units``, spent only on tracks at risk). Then, in order
of what matters most:

1. the packed inputs of the tracks at risk (live tracks the whole-frame pass missed, the
   longest unseen first), as long as they leave the band rotation its share: the units per
   frame that visit every band tile once per ``scan_period_s`` (``reserve``); the first
   packed input is held back neither by the reserve nor by a debt;
2. the band tiles not looked at for longest, while they fit in the budget; a tile that would
   be older than ``scan_period_s`` by the next frame runs even past the budget, once per frame,
   so the budget is never exceeded by more than one pass;
3. more packed inputs for the tracks in the room no tile fits in (none is left idle).

The bank is charged what a frame spent over the budget (a due tile, banked credit) and
credited what it spent under it; a debt is paid by the tiles that are not due and by the
tracks' further packed inputs, so the average over many frames stays at the budget.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.detection.config import BAND_ROW_STRETCH, STREAM_MIN_HITS, STREAM_MISSED_IOU, DetectionConfig, StreamConfig
from pedenv.detection.geometry import CameraGeometry
from pedenv.detection.levels import HeightLine, placing_geometry, plan_level, pyramid
from pedenv.detection.tiling import Pass, round32, units
from pedenv.detection.track_search import MIN_BOX_HEIGHT_PX, searchable

#: Most tiles of one level's band in ``stream``'s rotation (it visits them over several frames; a
#: bound against an absurd band only: 64 packed-input-wide tiles cover a 4K frame at x2 twice over).
BAND_MAX_TILES = 64


@dataclass(frozen=True)
class Tile:
    """One band tile of the rotation: ``key`` (level, tile) stays the same while the band does."""

    key: tuple[int, int]
    step: Pass

    @property
    def units(self) -> float:
        return units(self.step.input_size)


def band_tiles(width: int, height: int, config: DetectionConfig, geometry: CameraGeometry | None,
               line: HeightLine | None) -> tuple[list[Tile], str]:
    """The finer levels' tiles of a ``width`` x ``height`` frame, each at most one packed input
    (``stream.packed_width`` px wide), over the rows from the calibration, the fitted ``line``
    or the whole image (:func:`pedenv.detection.levels.plan_level`), and a note per level."""
    tiles, notes = [], []
    geometry = placing_geometry(geometry, width, height, config)  # the ground band, once per frame
    levels = pyramid(width, height, config)[1:]
    for li, level in enumerate(levels):
        passes, note = plan_level(level, width, height, config, geometry, line, finest=li == len(levels) - 1,
                                  tiles=(config.stream.packed_width, BAND_MAX_TILES))
        passes = one_row(passes, BAND_ROW_STRETCH)
        tiles += [Tile((li, ti), p) for ti, p in enumerate(passes)]
        notes.append(note)
    return tiles, "; ".join(notes)


def one_row(passes: list[Pass], stretch: float) -> list[Pass]:
    """A level's tiles in two rows, as one row of taller tiles over the same rows when the band is at
    most ``stretch`` tile heights tall (the same image px, fewer input px: a band 6 px taller than
    one tile no longer costs a second row of square tiles); otherwise ``passes`` as they are."""
    tops = sorted({p.region[1] for p in passes})
    if len(tops) != 2:
        return passes
    y0, y1 = tops[0], max(p.region[3] for p in passes)
    first = [p for p in passes if p.region[1] == y0]
    if y1 - y0 > stretch * (first[0].region[3] - y0):
        return passes
    out = []
    for p in first:
        x0, _, x1, _ = p.region
        scale = p.input_size[1] / (x1 - x0)
        out.append(Pass((x0, y0, x1, y1), (round32((y1 - y0) * scale), p.input_size[1]), p.kind))
    return out


def tracks_at_risk(predicted: np.ndarray, hits: np.ndarray, unseen_s: np.ndarray, found: np.ndarray,
                   image_size: tuple[int, int], min_hits: int = STREAM_MIN_HITS) -> np.ndarray:
    """Rows of the tracks to look for in crops, most at risk first.

    predicted: (T, 4) px, the tracks' expected boxes; hits: (T,) detections so far;
    unseen_s: (T,) seconds since each was last detected; found: (N, 4) px, the whole-frame
    pass's boxes; image_size: (height, width). A track is looked for when detected at least
    ``min_hits`` times, mostly inside the image, and overlapped by no found box by
    more than ``missed_iou``. Order: longest unseen first, then most hits.
    """
    predicted = np.asarray(predicted, float).reshape(-1, 4)
    if not len(predicted):
        return np.zeros(0, np.int64)
    usable = searchable(predicted, hits, found, image_size, min_hits=min_hits,
                        min_height_px=MIN_BOX_HEIGHT_PX, missed_iou=STREAM_MISSED_IOU)
    rows = np.flatnonzero(usable)
    return rows[np.lexsort((-np.asarray(hits)[rows], -np.asarray(unseen_s, float)[rows]))]


@dataclass(frozen=True)
class FramePlan:
    """What a frame runs beyond the whole-frame pass: ``packed`` packed inputs for the tracks,
    the rows of the band tiles (oldest first), the units the rotation needs per frame, whether a
    tile ran past the budget (it was due), the frame's ``budget`` and the ``credit`` it could
    spend on top (units)."""

    packed: int
    tiles: list[int]
    reserve_units: float
    over_budget: bool
    budget: float = 0.0
    credit: float = 0.0


def plan_frame(full_units: float, packed_units: float, packed_wanted: int, tile_units: np.ndarray,
               tile_age_s: np.ndarray, dt_s: float, config: StreamConfig, credit: float = 0.0) -> FramePlan:
    """The passes of one frame (module doc). tile_units, tile_age_s: (N,) per band tile (age:
    seconds since it was last looked at, inf if never); dt_s: the time to the next frame, s;
    credit: units banked by earlier frames (negative: owed), see :class:`CreditBank`."""
    tile_units = np.asarray(tile_units, float)
    tile_age_s = np.asarray(tile_age_s, float)
    budget = config.budget_units
    credit = min(credit, config.credit_units)
    allowance = budget + credit
    reserve = float(tile_units.sum()) * min(dt_s / config.scan_period_s, 1.0)
    spent, packed = full_units, 0
    while packed < packed_wanted:
        # the most at risk first, even owing (the debt is paid by the tiles), then the rotation's share
        room = max(allowance, budget) if packed == 0 else allowance - reserve
        if spent + packed_units > room + 1e-9:
            break
        spent += packed_units
        packed += 1
    chosen, over = [], False
    for i in np.argsort(-tile_age_s, kind="stable"):
        if spent + tile_units[i] <= min(budget, allowance) + 1e-9:
            spent += tile_units[i]
        elif not over and tile_age_s[i] + dt_s > config.scan_period_s:
            spent, over = spent + tile_units[i], True
        else:
            break
        chosen.append(int(i))
    while packed < packed_wanted and spent + packed_units <= allowance + 1e-9:  # the room no tile fits in
        spent += packed_units
        packed += 1
    return FramePlan(packed, chosen, reserve, over, budget, credit)


@dataclass
class CreditBank:
    """Units a stream has saved (positive) or owes (negative) against ``budget_units`` per frame.

    After each frame the bank gains the budget minus what the frame spent, capped at
    ``credit_units`` (0: no saving); a debt deeper than one frame's budget is forgiven (a frame
    always pays its whole-frame pass and a due tile). Cold starts are not charged: they are
    counted apart (``run.json``: ``cold_starts``, ``units_per_frame_after_cold_starts``).
    """

    credit: float = 0.0

    def charge(self, spent: float, config: StreamConfig) -> None:
        """A frame that spent ``spent`` units."""
        self.credit = float(np.clip(self.credit + config.budget_units - spent, -config.budget_units,
                                    config.credit_units))
