"""Where to spend the pose network's pixels: the detection config, the far-person band, the passes.

``fast``: one pass over the whole frame, the input fitted to the frame's aspect.
``far``: that pass plus tiles at native or upscaled resolution over the image band where a
person ``near_m``..``far_m`` away can stand (the ground there, up to ``top_m`` above it),
computed from the camera's intrinsics, height and tilt (ego pitch and roll included). A
camera looking down, one without calibration, or a band that misses the image gets the
whole image tiled instead (the plan says why).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from pedenv.errors import InputError

MODES = ("fast", "far")
STRIDE = 32


@dataclass(frozen=True)
class DetectionConfig:
    """Tunables of the detection passes (validated; a bad value raises ValueError naming the field).

    mode: ``fast`` (one pass) or ``far`` (the pass plus tiles).
    base_long_side: long side of the whole-frame pass's input, px (multiple of 32, 160..2048);
        the short side follows the frame's aspect. Raising it finds smaller people, costs more.
    tile_width: width of one tile's network input, px (multiple of 32, 160..1280).
    tile_overlap: overlap of neighbouring tiles, a fraction of the tile (0..0.5); it must exceed
        the width of the widest person the tiles are meant for, so each is whole in one tile.
    band_upscale: scale of the band tiles (1 = native pixels, 1..4); raising it finds
        farther people, costs its square.
    whole_image_scale: scale of the tiles when the whole image is tiled (0.25..4).
    near_m, far_m: distances bounding the band, metres (0.5 <= near < far <= 1000).
    top_m: height above the ground the band reaches, metres (0.5..5; a tall person 2 m).
    band_margin_px: rows added above and below the band, px (0..200), for pitch noise.
    max_pitch_down_deg: a camera tilted down more than this is "looking down": whole image tiled (1..89).
    max_pitch_up_deg: a camera tilted up more than this sees sky, no ground: whole image tiled (1..89).
    max_tiles: at most this many tiles; the tile scale is lowered to fit (1..64).
    edge_margin_px: a detection within this many input px of an inner tile edge counts as cut (0..64).
    """

    mode: str = "far"
    base_long_side: int = 640
    tile_width: int = 640
    tile_overlap: float = 0.25
    band_upscale: float = 2.0
    whole_image_scale: float = 1.0
    near_m: float = 15.0
    far_m: float = 150.0
    top_m: float = 2.2
    band_margin_px: int = 16
    max_pitch_down_deg: float = 20.0
    max_pitch_up_deg: float = 30.0
    max_tiles: int = 12
    edge_margin_px: int = 16

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"DetectionConfig.mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        ranges = {"base_long_side": (160, 2048), "tile_width": (160, 1280), "tile_overlap": (0.0, 0.5),
                  "band_upscale": (1.0, 4.0), "whole_image_scale": (0.25, 4.0), "near_m": (0.5, 1000.0),
                  "far_m": (0.5, 1000.0), "top_m": (0.5, 5.0), "band_margin_px": (0, 200),
                  "max_pitch_down_deg": (1.0, 89.0), "max_pitch_up_deg": (1.0, 89.0), "max_tiles": (1, 64),
                  "edge_margin_px": (0, 64)}
        for name, (low, high) in ranges.items():
            value = getattr(self, name)
            integer = isinstance(low, int)
            ok = not isinstance(value, bool) and isinstance(value, int if integer else (int, float))
            if not ok or not low <= value <= high:
                kind = "an integer" if integer else "a number"
                raise ValueError(f"DetectionConfig.{name} must be {kind} in [{low}, {high}], got {value!r}")
        for name in ("base_long_side", "tile_width"):
            if getattr(self, name) % STRIDE:
                raise ValueError(f"DetectionConfig.{name} must be a multiple of {STRIDE}, got {getattr(self, name)}")
        if self.near_m >= self.far_m:
            raise ValueError(f"DetectionConfig.near_m ({self.near_m}) must be below far_m ({self.far_m})")

    @classmethod
    def named(cls, mode: str, **changes) -> DetectionConfig:
        """The config of a mode (``fast`` or ``far``) with some fields changed."""
        if mode not in MODES:
            raise ValueError(f"detection mode must be one of {', '.join(MODES)}, got {mode!r}")
        return replace(cls(mode=mode), **changes)

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _round32(value: float) -> int:
    return max(STRIDE, int(math.ceil(value / STRIDE - 1e-9)) * STRIDE)


def fit_input(width: int, height: int, long_side: int) -> tuple[int, int]:
    """Network input (height, width) with ``long_side`` along the image's long side and the
    other side fitted to the aspect, rounded up to a multiple of 32 (1600x900 -> 384x640)."""
    if width >= height:
        return _round32(long_side * height / width), long_side
    return long_side, _round32(long_side * width / height)


@dataclass(frozen=True)
class CameraGeometry:
    """What the band needs: intrinsics, the camera's tilt relative to gravity and its height.

    K: (3, 3) pixels. cam_to_level: (3, 3) rotation, optical camera frame (x right, y down,
    z forward) -> a frame with z up (gravity-aligned; its yaw does not matter).
    height_m: camera height above the ground under it, metres.
    """

    K: np.ndarray
    cam_to_level: np.ndarray
    height_m: float

    @classmethod
    def level(cls, K, height_m: float, pitch_down_rad: float = 0.0, roll_rad: float = 0.0) -> CameraGeometry:
        """A camera ``height_m`` above flat ground, pitched down by ``pitch_down_rad``, rolled by ``roll_rad``."""
        base = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # optical -> (x right, y forward, z up)
        cp, sp, cr, sr = math.cos(pitch_down_rad), math.sin(pitch_down_rad), math.cos(roll_rad), math.sin(roll_rad)
        pitch = np.array([[1, 0, 0], [0, cp, sp], [0, -sp, cp]])  # about x: forward axis goes down
        roll = np.array([[cr, 0, sr], [0, 1, 0], [-sr, 0, cr]])  # about the forward axis
        return cls(np.asarray(K, float), pitch @ roll @ base, float(height_m))

    @classmethod
    def from_frame(cls, frame) -> CameraGeometry:
        """From a :class:`~pedenv.records.Frame`: camera intrinsics and mount, ego pitch and roll."""
        cam_to_vehicle = frame.camera.cam_to_vehicle
        rotation = frame.ego.rotation @ cam_to_vehicle[:3, :3]
        height = float((frame.ego.rotation @ cam_to_vehicle[:3, 3])[2])
        return cls(np.asarray(frame.camera.intrinsics, float), rotation, height)


@dataclass(frozen=True)
class Band:
    """Rows ``[top, bottom)`` of the image where far people can stand, or the reason there is none."""

    top: int
    bottom: int
    reason: str = ""


def far_band(geometry: CameraGeometry | None, width: int, height: int, config: DetectionConfig) -> Band | None:
    """The image rows where a person ``near_m``..``far_m`` away stands; None -> tile the whole image.

    None comes back (with no error) for: no calibration, a camera looking down by more than
    ``max_pitch_down_deg`` or up by more than ``max_pitch_up_deg``, a camera below the
    ground, or a band that lies wholly above or below the image.
    """
    if geometry is None:
        return None
    R, K = geometry.cam_to_level, geometry.K
    forward = R[:, 2]
    pitch_down = math.degrees(math.asin(float(np.clip(-forward[2], -1.0, 1.0))))
    if pitch_down > config.max_pitch_down_deg or -pitch_down > config.max_pitch_up_deg or geometry.height_m <= 0:
        return None
    horizontal = np.array([forward[0], forward[1], 0.0])
    horizontal /= np.linalg.norm(horizontal)
    left = np.cross([0.0, 0.0, 1.0], horizontal)
    d = np.geomspace(config.near_m, config.far_m, 24)[:, None, None]
    lateral = np.linspace(-3.0, 3.0, 61)[None, :, None] * d  # +-72 deg around the axis
    z = np.array([-geometry.height_m, config.top_m - geometry.height_m])[None, None, :]
    points = d[..., None] * horizontal + lateral[..., None] * left + z[..., None] * np.array([0, 0, 1.0])
    cam = points.reshape(-1, 3) @ R  # level -> camera: R^T p, as row vectors
    ahead = cam[:, 2] > 0.1
    uv = cam[ahead] @ K.T
    uv = uv[:, :2] / uv[:, 2:3]
    inside = (uv[:, 0] >= 0) & (uv[:, 0] <= width)
    if not inside.any():
        return None
    top = int(math.floor(uv[inside, 1].min())) - config.band_margin_px
    bottom = int(math.ceil(uv[inside, 1].max())) + config.band_margin_px
    top, bottom = max(top, 0), min(bottom, height)
    if bottom - top < 8:
        return None  # the band lies above or below the image
    return Band(top, bottom)


@dataclass(frozen=True)
class Pass:
    """One network pass: the image region ``(x0, y0, x1, y1)`` (px, end exclusive) scaled into
    ``input_size`` (height, width); ``kind`` is ``full``, ``band`` or ``tile`` (whole image tiled)."""

    region: tuple[int, int, int, int]
    input_size: tuple[int, int]
    kind: str


def _starts(length: int, window: int, overlap: float) -> list[int]:
    if window >= length:
        return [0]
    step = window * (1.0 - overlap)
    n = int(math.ceil((length - window) / step)) + 1
    return [int(round(i * (length - window) / (n - 1))) for i in range(n)]


def _tiles(region: tuple[int, int, int, int], scale: float, config: DetectionConfig, kind: str) -> list[Pass]:
    x0, y0, x1, y1 = region
    window_w = max(1, int(round(config.tile_width / scale)))
    window_h = max(1, int(round(config.tile_width / scale)))  # square tiles at most; bands are shorter
    tiles = []
    for ty in _starts(y1 - y0, window_h, config.tile_overlap):
        th = min(window_h, y1 - y0)
        for tx in _starts(x1 - x0, window_w, config.tile_overlap):
            tw = min(window_w, x1 - x0)
            box = (x0 + tx, y0 + ty, x0 + tx + tw, y0 + ty + th)
            tiles.append(Pass(box, (_round32(th * scale), _round32(tw * scale)), kind))
    return tiles


def plan_passes(width: int, height: int, config: DetectionConfig,
                geometry: CameraGeometry | None = None) -> tuple[list[Pass], str]:
    """The passes for a ``width`` x ``height`` image, and a note on how the tiles were chosen.

    Raises InputError for an image smaller than 8x8 px.
    """
    if width < 8 or height < 8:
        raise InputError(f"image of {width}x{height} px is too small for the pose network (at least 8x8)")
    passes = [Pass((0, 0, width, height), fit_input(width, height, config.base_long_side), "full")]
    if config.mode == "fast":
        return passes, "one pass"
    band = far_band(geometry, width, height, config)
    if band is None:
        region, scale, kind = (0, 0, width, height), config.whole_image_scale, "tile"
        note = "no calibration" if geometry is None else "camera looks down or up, or the band misses the image"
        note = f"whole image tiled ({note})"
    else:
        region, scale, kind = (0, band.top, width, band.bottom), config.band_upscale, "band"
        note = f"band rows {band.top}-{band.bottom}"
    tiles = _tiles(region, scale, config, kind)
    while len(tiles) > config.max_tiles and scale > 0.05:
        scale *= 0.85  # bigger windows: fewer tiles, at a lower scale
        tiles = _tiles(region, scale, config, kind)
    base_scale = passes[0].input_size[1] / width if width >= height else passes[0].input_size[0] / height
    if scale <= base_scale * 1.05:
        return passes, note + "; tiles would add nothing over the whole-frame pass"
    return passes + tiles, f"{note}; {len(tiles)} tiles at scale {scale:.2f}"
