"""Where to spend the pose network's pixels: the detection config, the ground band, the passes.

``fast``: one pass over the whole frame, the input fitted to the frame's aspect.
``far``: that pass plus finer levels (:mod:`pedenv.pose.levels`), each over the image band
where its people can stand: the ground at the distances where they have the level's
heights in px, up to ``top_m`` above it, from the camera's intrinsics, height and tilt
(ego pitch and roll included). This module holds the config, the camera geometry, the band
of a distance range and the tiling of a region.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from pedenv.errors import InputError
from pedenv.pose.stream_config import CascadeConfig, StreamConfig, section_of
from pedenv.validation import check_below, check_choice, check_fields, check_number, choice, count, number, shown

if TYPE_CHECKING:
    from pedenv.records import Camera, Frame

MODES = ("fast", "far", "stream")
STRIDE = 32
#: Input px of one network unit, the cost measure of detection (a 384x640 input).
UNIT_PX = 384 * 640
#: Most levels of the pyramid (``level_scales``): each costs at least one network pass per frame.
MAX_LEVELS = 8


def units(input_size: tuple[int, int]) -> float:
    """Network units of one input of ``(height, width)`` px."""
    return input_size[0] * input_size[1] / UNIT_PX


@dataclass(frozen=True)
class DetectionConfig:
    """Tunables of the detection passes, section ``detection`` of :class:`pedenv.config.Config`
    (validated by :mod:`pedenv.validation`; a bad value raises InputError naming ``detection.field``).

    ``far`` runs a pyramid of *levels*: the whole-frame pass, then one level per scale of
    ``level_scales``, each over the image rows where the people it is for can stand. A level
    at scale ``s`` is for people whose height in the image lies in
    ``[min_person_px / s, min_person_px / s_coarser)`` px (the whole-frame pass: at least
    ``min_person_px / its scale``). Those rows come from the calibration (the ground at the
    distances where such people stand) or, without a usable calibration, from a line fitted
    to the heights and foot rows of the people the coarser levels found.

    mode: ``fast`` (one pass), ``far`` (the levels) or ``stream`` (consecutive frames: the
        levels' tiles in rotation, :mod:`pedenv.pose.stream`; on a single image as ``far``).
    base_long_side: long side of the whole-frame pass's input, px (multiple of 32, 160..2048);
        the short side follows the frame's aspect. Raising it finds smaller people, costs more.
    tile_width: longest side of one tile's network input, px (multiple of 32, 160..4096); a
        level's rows wider than this are cut into overlapping tiles.
    tile_overlap: overlap of neighbouring tiles, a fraction of the tile (0..0.5); it must exceed
        the width of the widest person the tiles are meant for, so each is whole in one tile.
    level_scales: scales of the far levels, ascending, each in [0.25, 4] (1 = native pixels), at
        most :data:`MAX_LEVELS` (8);
        a scale at or below the whole-frame pass's is skipped. Adding a finer scale finds
        smaller people and costs its square times the width of its rows.
    min_person_px: height in a level's network input, px, of the smallest person that level
        is trusted to find (20..400); lowering it hands people to coarser, cheaper levels.
    max_person_px: a level detection taller than this in its network input, px, is dropped
        (100..4000): a fragment of someone too large for that level (whole-frame pass exempt).
    whole_image_max_mpx: a level whose rows are unknown (no usable calibration, too few
        people found to fit them) runs over the whole image when that costs at most this many
        network input megapixels (0.1..50); else it is skipped. The finest level is not skipped:
    whole_image_finest_mpx: the finest level with unknown rows runs over the whole image, at its
        scale lowered so that costs at most this many network input megapixels (0.1..50; 6 holds
        a 1600x900 image at x2: about 23 units). So a street photo with only small people in it
        (none found to fit the rows) is still searched at the finest level.
    near_m, far_m: distances bounding every band, metres (0.5 <= near < far <= 1000).
    top_m: height above the ground the band reaches, metres (0.5..5; a tall person 2 m); the
        tallest person assumed when heights in px are turned into distances.
    short_person_m: the shortest person assumed when heights in px are turned into
        distances, metres (0.5..2.5, below top_m).
    band_margin_px: rows added above and below each band, px (0..200), for pitch noise.
    fit_min_people: people (whole, scoring at least fit_min_score) needed to fit the rows of
        finer levels without calibration (2..100).
    fit_min_score: a person found by a coarser level counts for that fit when scoring at least
        this (0..1). Lowering it fits more frames (a dark or sparse one) from less sure people.
    fit_margin: rows added above and below a fitted band, a fraction of the level's tallest
        person (0..2), for people taller or shorter than the fit and for its error.
    sure_score: level detections scoring at least this are kept without the skeleton check (0..1).
    plausible_keypoint_conf: a level detection scoring below sure_score is kept only when its
        17 keypoint confidences average at least this (0..1): a person, not a pole or a cone.
    max_pitch_down_deg: a camera tilted down more than this is "looking down": fitted rows (1..89).
    max_pitch_up_deg: a camera tilted up more than this sees sky, no ground: fitted rows (1..89).
    max_tiles: at most this many tiles per level; the level's scale is lowered to fit (1..64).
    edge_margin_px: a detection within this many input px of an inner tile edge counts as cut (0..64).
    cascade: low-scoring small persons verified at a higher zoom (``far``, ``stream``): :class:`CascadeConfig`.
    stream: the ``stream`` mode's budget and rotation: :class:`StreamConfig`.
    """

    mode: str = choice("far", MODES)
    base_long_side: int = count(640, 160, 2048)
    tile_width: int = count(3840, 160, 4096)
    tile_overlap: float = number(0.25, 0.0, 0.5)
    level_scales: tuple[float, ...] = (1.0, 2.0)
    min_person_px: float = number(80.0, 20.0, 400.0)
    max_person_px: float = number(480.0, 100.0, 4000.0)
    whole_image_max_mpx: float = number(2.1, 0.1, 50.0)
    whole_image_finest_mpx: float = number(6.0, 0.1, 50.0)
    near_m: float = number(5.0, 0.5, 1000.0)
    far_m: float = number(150.0, 0.5, 1000.0)
    top_m: float = number(2.2, 0.5, 5.0)
    short_person_m: float = number(1.5, 0.5, 2.5)
    band_margin_px: int = count(16, 0, 200)
    fit_min_people: int = count(3, 2, 100)
    fit_min_score: float = number(0.35, 0.0, 1.0)
    fit_margin: float = number(0.5, 0.0, 2.0)
    sure_score: float = number(0.5, 0.0, 1.0)
    plausible_keypoint_conf: float = number(0.5, 0.0, 1.0)
    max_pitch_down_deg: float = number(20.0, 1.0, 89.0)
    max_pitch_up_deg: float = number(30.0, 1.0, 89.0)
    max_tiles: int = count(12, 1, 64)
    edge_margin_px: int = count(16, 0, 64)
    cascade: CascadeConfig = CascadeConfig()
    stream: StreamConfig = StreamConfig()

    def __post_init__(self) -> None:
        object.__setattr__(self, "cascade", section_of(CascadeConfig, "cascade", self.cascade))
        object.__setattr__(self, "stream", section_of(StreamConfig, "stream", self.stream))
        check_fields("detection", self)
        scales = self.level_scales
        if not isinstance(scales, tuple) or not 1 <= len(scales) <= MAX_LEVELS:
            raise InputError(f"detection.level_scales must be a non-empty tuple of at most {MAX_LEVELS} numbers, "
                             f"got {shown(scales)}")
        for value in scales:
            check_number("detection.level_scales", value, 0.25, 4.0)
        if list(scales) != sorted(set(scales)):
            raise InputError(f"detection.level_scales must be ascending without repeats, got {shown(scales)}")
        for name in ("base_long_side", "tile_width"):
            if getattr(self, name) % STRIDE:
                raise InputError(f"detection.{name} must be a multiple of {STRIDE}, got {getattr(self, name)}")
        check_below("detection.near_m", self.near_m, "detection.far_m", self.far_m)
        check_below("detection.short_person_m", self.short_person_m, "detection.top_m", self.top_m)

    @classmethod
    def named(cls, mode: str, **changes: Any) -> DetectionConfig:  # changes: field values
        """The config of a mode (``fast``, ``far`` or ``stream``) with some fields changed."""
        check_choice("detection mode", mode, MODES)
        return replace(cls(mode=mode), **changes)

    def to_dict(self) -> dict:
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else
                         v.to_dict() if hasattr(v, "to_dict") else v) for f in fields(self)}


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
    def level(cls, K: np.ndarray, height_m: float, pitch_down_rad: float = 0.0,
              roll_rad: float = 0.0) -> CameraGeometry:
        """A camera ``height_m`` above flat ground, pitched down by ``pitch_down_rad``, rolled by ``roll_rad``."""
        base = np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]])  # optical -> (x right, y forward, z up)
        cp, sp, cr, sr = math.cos(pitch_down_rad), math.sin(pitch_down_rad), math.cos(roll_rad), math.sin(roll_rad)
        pitch = np.array([[1, 0, 0], [0, cp, sp], [0, -sp, cp]])  # about x: forward axis goes down
        roll = np.array([[cr, 0, sr], [0, 1, 0], [-sr, 0, cr]])  # about the forward axis
        return cls(np.asarray(K, float), pitch @ roll @ base, float(height_m))

    @classmethod
    def of_camera(cls, camera: Camera) -> CameraGeometry:
        """From a :class:`~pedenv.records.Camera` on a level vehicle (its mount's rotation and height)."""
        mount = camera.cam_to_vehicle
        return cls(np.asarray(camera.intrinsics, float), mount[:3, :3], float(mount[2, 3]))

    @classmethod
    def from_frame(cls, frame: Frame) -> CameraGeometry:
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


def usable_calibration(geometry: CameraGeometry | None, config: DetectionConfig) -> bool:
    """Whether the calibration can place the far band: given, the camera above the ground,
    tilted down by at most ``max_pitch_down_deg`` and up by at most ``max_pitch_up_deg``."""
    if geometry is None or geometry.height_m <= 0:
        return False
    pitch_down = math.degrees(math.asin(float(np.clip(-geometry.cam_to_level[2, 2], -1.0, 1.0))))
    return pitch_down <= config.max_pitch_down_deg and -pitch_down <= config.max_pitch_up_deg


def ground_rows(geometry: CameraGeometry, width: int, height: int, near_m: float, far_m: float,
                config: DetectionConfig, max_height_px: float = math.inf) -> Band | None:
    """Rows where a person ``near_m``..``far_m`` away stands (the ground there up to ``top_m``,
    or up to the height a person ``max_height_px`` tall in the image has there, if lower;
    +-72 deg around the optical axis, plus ``band_margin_px``); None when they miss the image."""
    R, K = geometry.cam_to_level, geometry.K
    forward = R[:, 2]
    horizontal = np.array([forward[0], forward[1], 0.0])
    horizontal /= max(float(np.linalg.norm(horizontal)), 1e-9)
    left = np.cross([0.0, 0.0, 1.0], horizontal)
    d = np.geomspace(near_m, far_m, 24)[:, None, None]
    lateral = np.linspace(-3.0, 3.0, 61)[None, :, None] * d  # +-72 deg around the axis
    head_m = np.minimum(config.top_m, max_height_px * d / float(K[1, 1]))  # (24, 1, 1) metres
    z = np.concatenate(np.broadcast_arrays(np.full_like(head_m, -geometry.height_m), head_m - geometry.height_m),
                       axis=2)
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


def far_band(geometry: CameraGeometry | None, width: int, height: int, config: DetectionConfig) -> Band | None:
    """The image rows where a person ``near_m``..``far_m`` away stands; None -> no usable band.

    None comes back (with no error) for: no calibration, a camera looking down by more than
    ``max_pitch_down_deg`` or up by more than ``max_pitch_up_deg``, a camera below the
    ground, or a band that lies wholly above or below the image.
    """
    if not usable_calibration(geometry, config):
        return None
    assert geometry is not None
    return ground_rows(geometry, width, height, config.near_m, config.far_m, config)


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


def _tiles(region: tuple[int, int, int, int], scale: float, config: DetectionConfig, kind: str) -> list[Pass]:
    x0, y0, x1, y1 = region
    window = max(1, int(round(config.tile_width / scale)))  # square tiles at most; bands are shorter
    tiles = []
    for ty in _starts(y1 - y0, window, config.tile_overlap):
        th = min(window, y1 - y0)
        for tx in _starts(x1 - x0, window, config.tile_overlap):
            tw = min(window, x1 - x0)
            box = (x0 + tx, y0 + ty, x0 + tx + tw, y0 + ty + th)
            tiles.append(Pass(box, (round32(th * scale), round32(tw * scale)), kind))
    return tiles


def tile_region(region: tuple[int, int, int, int], scale: float, config: DetectionConfig,
                kind: str) -> tuple[list[Pass], float]:
    """Tiles of ``region`` (px) at ``scale``, at most ``max_tiles`` (the scale lowered to fit);
    returns the tiles and the scale they run at."""
    tiles = _tiles(region, scale, config, kind)
    while len(tiles) > config.max_tiles and scale > 0.05:
        scale *= 0.85  # bigger windows: fewer tiles, at a lower scale
        tiles = _tiles(region, scale, config, kind)
    return tiles, scale


def full_pass(width: int, height: int, config: DetectionConfig) -> Pass:
    """The whole-frame pass of a ``width`` x ``height`` image; InputError below 8x8 px."""
    if width < 8 or height < 8:
        raise InputError(f"image of {width}x{height} px is too small for the pose network (at least 8x8)")
    return Pass((0, 0, width, height), fit_input(width, height, config.base_long_side), "full")
