"""Passes and tiles: the network input of an image region, and a region cut into tiles.

A *pass* is one network run over an image region scaled into an input; the whole-frame pass
has its input fitted to the frame's aspect; a level's rows wider than ``tile_width`` are cut
into overlapping *tiles*. Costs are counted in *units* (one 384x640 input).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from pedenv.detection.config import MAX_TILES, STRIDE, TILE_OVERLAP, DetectionConfig
from pedenv.errors import InputError

#: Input px of one network unit, the cost measure of detection (a 384x640 input).
UNIT_PX = 384 * 640


def units(input_size: tuple[int, int]) -> float:
    """Network units of one input of ``(height, width)`` px."""
    return input_size[0] * input_size[1] / UNIT_PX


def round32(value: float) -> int:
    """``value`` (input px) rounded up to the network's stride (32), at least one stride."""
    return max(STRIDE, int(math.ceil(value / STRIDE - 1e-9)) * STRIDE)


def fit_input(width: int, height: int, long_side: int) -> tuple[int, int]:
    """Network input (height, width) with ``long_side`` along the image's long side and the
    other side fitted to the aspect, rounded up to a multiple of 32 (1600x900 -> 384x640)."""
    if width >= height:
        return round32(long_side * height / width), long_side
    return long_side, round32(long_side * width / height)


@dataclass(frozen=True)
class Pass:
    """One network pass: the image region ``(x0, y0, x1, y1)`` (px, end exclusive) scaled into
    ``input_size`` (height, width); ``kind`` is ``full`` (the whole-frame pass), ``band``
    (a level over rows from the calibration or a fit) or ``tile`` (a level over the whole image)."""

    region: tuple[int, int, int, int]
    input_size: tuple[int, int]
    kind: str

    @property
    def scale(self) -> float:
        """Network input px per image px."""
        x0, y0, x1, y1 = self.region
        return min(self.input_size[0] / (y1 - y0), self.input_size[1] / (x1 - x0))


def _starts(length: int, window: int, overlap: float) -> list[int]:
    if window >= length:
        return [0]
    step = window * (1.0 - overlap)
    n = int(math.ceil((length - window) / step)) + 1
    return [int(round(i * (length - window) / (n - 1))) for i in range(n)]


def _tiles(region: tuple[int, int, int, int], scale: float, tile_width: int, kind: str) -> list[Pass]:
    x0, y0, x1, y1 = region
    window = max(1, int(round(tile_width / scale)))  # square tiles at most; bands are shorter
    tiles = []
    for ty in _starts(y1 - y0, window, TILE_OVERLAP):
        th = min(window, y1 - y0)
        for tx in _starts(x1 - x0, window, TILE_OVERLAP):
            tw = min(window, x1 - x0)
            box = (x0 + tx, y0 + ty, x0 + tx + tw, y0 + ty + th)
            tiles.append(Pass(box, (round32(th * scale), round32(tw * scale)), kind))
    return tiles


def tile_region(region: tuple[int, int, int, int], scale: float, tile_width: int, kind: str,
                max_tiles: int = MAX_TILES) -> tuple[list[Pass], float]:
    """Tiles of ``region`` (px) at ``scale``, each input at most ``tile_width`` px wide, at most
    ``max_tiles`` (the scale lowered to fit); returns the tiles and the scale they run at."""
    tiles = _tiles(region, scale, tile_width, kind)
    while len(tiles) > max_tiles and scale > 0.05:
        scale *= 0.85  # bigger windows: fewer tiles, at a lower scale
        tiles = _tiles(region, scale, tile_width, kind)
    return tiles, scale


def full_pass(width: int, height: int, config: DetectionConfig) -> Pass:
    """The whole-frame pass of a ``width`` x ``height`` image; InputError below 8x8 px."""
    if width < 8 or height < 8:
        raise InputError(f"image of {width}x{height} px is too small for the pose network (at least 8x8)")
    return Pass((0, 0, width, height), fit_input(width, height, config.base_long_side), "full")
