"""The ``far`` mode's pyramid: which scale runs over which image rows.

A :class:`Level` is a scale and the range of person heights (px of the image) it is for:
the whole-frame pass finds the people tall enough at its scale, each finer level those
``min_person_px / scale`` px tall and up, below the coarser level's limit. A level runs
only over the rows where such people can stand: from the calibration (the ground at the
distances where a 1.5-2.2 m person has that height), or, without a usable calibration
(none, or a camera looking down), from a :class:`HeightLine` fitted to the people the
coarser levels found (on flat ground a person's height in px grows linearly with the row of
their feet, and is zero at the horizon). With neither, a level covers the whole image if
that costs at most ``whole_image_max_mpx`` network input megapixels, else it is skipped; the
finest level then covers the whole image at a scale lowered to ``whole_image_finest_mpx``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pedenv.detection.config import (
    BAND_MARGIN_PX,
    FIT_MARGIN,
    MAX_TILES,
    SHORT_PERSON_M,
    TOP_M,
    WHOLE_IMAGE_FINEST_MPX,
    WHOLE_IMAGE_MAX_MPX,
    DetectionConfig,
)
from pedenv.detection.geometry import Band, CameraGeometry, far_band, ground_rows
from pedenv.detection.tiling import Pass, full_pass, tile_region


@dataclass(frozen=True)
class Level:
    """One scale of the pyramid: network input px per image px, and the people it is for
    (height in image px, ``[min_height_px, max_height_px)``; the whole-frame pass's max is inf)."""

    scale: float
    min_height_px: float
    max_height_px: float


def pyramid(width: int, height: int, config: DetectionConfig) -> list[Level]:
    """The levels for a ``width`` x ``height`` image: the whole-frame pass, then each of
    ``level_scales`` finer than the level before it (``fast``: the whole-frame pass only)."""
    base = full_pass(width, height, config)
    levels = [Level(base.scale, config.min_person_px / base.scale, math.inf)]
    if config.mode == "fast":
        return levels
    for scale in config.level_scales:
        if scale > levels[-1].scale * 1.05:
            levels.append(Level(scale, config.min_person_px / scale, levels[-1].min_height_px))
    return levels


@dataclass(frozen=True)
class HeightLine:
    """``height_px = slope * foot_row + offset``: people's height against the row of their feet
    (px), fitted to the people found; valid for slope > 0 (taller lower in the image)."""

    slope: float
    offset: float
    people: int

    @classmethod
    def fit(cls, boxes: np.ndarray, min_people: int, image_height: int) -> HeightLine | None:
        """The line through boxes (N, 4) px ``[u0, v0, u1, v1]``, or None: fewer than
        ``min_people`` boxes (or inliers), feet spread over less than 5 % of the image's rows,
        or a slope that is not positive. One refit on the boxes within 30 % of the first line;
        ``people`` counts those within 30 % of the final one."""
        boxes = np.asarray(boxes, float).reshape(-1, 4)
        feet, heights = boxes[:, 3], boxes[:, 3] - boxes[:, 1]
        if len(feet) < min_people or np.ptp(feet) < 0.05 * image_height:
            return None
        slope, offset = np.polyfit(feet, heights, 1)
        inliers = np.abs(slope * feet + offset - heights) <= 0.3 * heights
        if inliers.sum() >= min_people and np.ptp(feet[inliers]) >= 0.05 * image_height:
            slope, offset = np.polyfit(feet[inliers], heights[inliers], 1)
            inliers = np.abs(slope * feet + offset - heights) <= 0.3 * heights
        if inliers.sum() < min_people or slope <= 0:
            return None
        return cls(float(slope), float(offset), int(inliers.sum()))

    def rows(self, low_px: float, high_px: float, margin_px: float, image_height: int) -> Band | None:
        """Rows where a person ``low_px``..``high_px`` tall stands (feet to head, plus
        ``margin_px`` above and below); None when they miss the image."""
        high_px = min(high_px, 4.0 * image_height)
        feet = [(h - self.offset) / self.slope for h in (low_px, high_px)]
        top = min(f - h for f, h in zip(feet, (low_px, high_px))) - margin_px
        bottom = max(feet) + margin_px
        top, bottom = max(int(math.floor(top)), 0), min(int(math.ceil(bottom)), image_height)
        return Band(top, bottom) if bottom - top >= 8 else None


def placing_geometry(geometry: CameraGeometry | None, width: int, height: int,
                     config: DetectionConfig) -> CameraGeometry | None:
    """``geometry`` when its calibration places the levels (usable, and the ground ``near_m``..``far_m``
    away lies in the image), else None (the rows come from a fit, or the whole image). Derived once
    per frame and handed to :func:`plan_level`."""
    return geometry if far_band(geometry, width, height, config) is not None else None


def calibrated_rows(level: Level, geometry: CameraGeometry, width: int, height: int,
                    config: DetectionConfig) -> Band | None:
    """Rows where the calibration puts the level's people: the ground where a person
    ``short_person_m``..``top_m`` tall has the level's heights in px, within ``near_m``..``far_m``,
    up to the head of the tallest of them (taller people there belong to a coarser level)."""
    focal = float(geometry.K[1, 1])
    near = max(config.near_m, focal * SHORT_PERSON_M / level.max_height_px)
    far = min(config.far_m, focal * TOP_M / level.min_height_px)
    if near >= far:
        return None
    return ground_rows(geometry, width, height, near, far, level.max_height_px)


def plan_level(level: Level, width: int, height: int, config: DetectionConfig, geometry: CameraGeometry | None,
               line: HeightLine | None, finest: bool = False,
               tiles: tuple[int, int] | None = None) -> tuple[list[Pass], str]:
    """The passes of one finer level and a note on how its rows were chosen (no passes: skipped).
    geometry: the camera when its calibration places the levels (:func:`placing_geometry`), else None.
    ``finest``: the pyramid's finest level, which covers the whole image when its rows are
    unknown (at a scale lowered to :data:`~pedenv.detection.config.WHOLE_IMAGE_FINEST_MPX`) instead of
    being skipped. ``tiles``: (tile width, most tiles) of the level; None: ``config.tile_width`` and
    :data:`~pedenv.detection.config.MAX_TILES` (``stream`` cuts its band into packed-input-wide tiles)."""
    scale = level.scale
    if geometry is not None:
        band, how = calibrated_rows(level, geometry, width, height, config), "calibration"
    elif line is not None:
        margin = FIT_MARGIN * min(level.max_height_px, height) + BAND_MARGIN_PX
        band, how = line.rows(level.min_height_px, level.max_height_px, margin, height), f"fit to {line.people}"
    elif width * height * scale**2 <= WHOLE_IMAGE_MAX_MPX * 1e6:
        band, how = Band(0, height), "whole image: no calibration, no fit"
    elif finest:
        scale = min(scale, math.sqrt(WHOLE_IMAGE_FINEST_MPX * 1e6 / (width * height)))
        band, how = Band(0, height), "whole image at the finest level: no calibration, too few people to fit"
    else:
        return [], f"x{level.scale:g} skipped: no calibration, too few people to fit"
    if band is None:
        return [], f"x{level.scale:g} skipped: its people would stand outside the image ({how})"
    kind = "tile" if (band.top, band.bottom) == (0, height) else "band"
    tile_width, max_tiles = tiles if tiles is not None else (config.tile_width, MAX_TILES)
    passes, scale = tile_region((0, band.top, width, band.bottom), scale, tile_width, kind, max_tiles)
    return passes, f"x{scale:.2f} rows {band.top}-{band.bottom} ({how}), {len(passes)} tiles"


def plan_passes(width: int, height: int, config: DetectionConfig,
                geometry: CameraGeometry | None = None) -> tuple[list[Pass], str]:
    """The passes known before any detection (the whole-frame pass and the levels whose rows
    come from the calibration or cover the whole image), and a note per level. Levels that
    wait for a fit are named in the note. Raises InputError for an image smaller than 8x8 px."""
    passes = [full_pass(width, height, config)]
    if config.mode == "fast":
        return passes, "one pass"
    placing = placing_geometry(geometry, width, height, config)
    notes = [] if placing is not None else [
        "no calibration" if geometry is None else "no usable calibration (camera looks down or up, or the band "
                                                  "misses the image)"]
    for level in pyramid(width, height, config)[1:]:  # the finest level's whole-image fallback waits for the fit
        more, note = plan_level(level, width, height, config, placing, None)
        passes += more
        notes.append(note)
    return passes, "; ".join(notes)
