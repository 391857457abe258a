"""Every detection setting: the passes (``detection``), the stream and cascade inside it, and the
track search (``redetect``); below them the algorithms' constants, each with its source.

These are sections of the run's :class:`pedenv.config.Config` (registered here with
:func:`pedenv.config.register_section`, so the core's config imports nothing of detection);
a bad value raises :class:`~pedenv.errors.InputError` naming ``section.field``. The words
(pass, level, band, tile, unit, packed input, ...) are those of :mod:`pedenv.detection`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any, TypeVar

from pedenv.config import drop_retired, register_section, retire_section
from pedenv.errors import InputError
from pedenv.validation import check_below, check_choice, check_fields, check_number, choice, count, flag, number, shown

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

_T = TypeVar("_T", bound="DataclassInstance")

MODES = ("fast", "far", "stream")
#: The network's stride: every input side is a multiple of it.
STRIDE = 32
#: Most levels of the pyramid (``level_scales``): each costs at least one network pass per frame.
MAX_LEVELS = 8

def section_of(kind: type[_T], name: str, value: object) -> _T:
    """``value`` as the nested section ``kind`` (a dict from ``config.json`` is built into it,
    naming ``detection.<name>`` and its valid fields when a field is unknown; a field that is no
    longer a setting is dropped when it holds today's fixed value, :func:`pedenv.config.drop_retired`)."""
    if isinstance(value, kind):
        return value
    if not isinstance(value, dict):
        raise InputError(f"detection.{name} must be an object of fields, got {type(value).__name__}")
    value = {RENAMED.get(k, k): v for k, v in value.items()}  # packed inputs were called mosaics
    value = drop_retired(f"detection.{name}", value, RETIRED.get(f"detection.{name}", {}))
    valid = {f.name for f in fields(kind)}
    unknown = sorted(str(k)[:40] for k in set(value) - valid)
    if unknown:
        raise InputError(f"unknown field(s) in detection.{name}: {', '.join(unknown[:5])}; "
                         f"valid: {', '.join(sorted(valid))}")
    return kind(**value)


def _fields(section: object) -> dict:
    return {f.name: (list(v) if isinstance(v := getattr(section, f.name), tuple) else
                     v.to_dict() if hasattr(v, "to_dict") else v) for f in fields(section)}  # type: ignore[arg-type]


@dataclass(frozen=True)
class CascadeConfig:
    """Persons the network scores below its threshold, verified at a higher zoom (``far``, ``stream``).

    A pass keeps persons scoring at least the network's ``score_threshold``. Those scoring
    :data:`CASCADE_MIN_SCORE` up to it, small enough to be far (boxes
    :data:`CASCADE_MIN_HEIGHT_PX`..:data:`CASCADE_MAX_HEIGHT_PX` tall), are *cascade candidates*:
    each is cropped, zoomed so the person is :data:`CASCADE_PERSON_PX` tall and packed several to
    one packed input; a candidate is kept when that zoomed pass finds a whole, plausible person at
    the same place (:mod:`pedenv.detection.cascade`). Measured on the real samples
    (``benchmarks/cascade_real.py``): ``far`` 40-80 px recall 53 -> 65 %, precision 94 -> 90 %,
    about 1 unit per image more.

    enabled: run the cascade. Off: fewer small far people found, about one unit a frame saved.
    max_units: at most this many units (packed inputs) per frame for the cascade (1..16; 3), the
        best-scoring candidates first. Raising it verifies more candidates in a crowded frame, at
        more cost (``stream`` fits them in the room its packed inputs leave first).
    """

    enabled: bool = flag(True)
    max_units: int = count(3, 1, 16)

    def __post_init__(self) -> None:
        check_fields("detection.cascade", self)

    def to_dict(self) -> dict:
        return _fields(self)


@dataclass(frozen=True)
class StreamConfig:
    """The ``stream`` detection over consecutive frames (:mod:`pedenv.detection.stream`).

    Every frame: the whole-frame pass; the live tracks it missed, cropped around their
    predicted boxes and packed several to one packed input; the far band's tiles in rotation; the
    cascade's candidates in the free room of those inputs. Costs are in units (one 384x640 input).

    budget_units: units per frame on average (1..64; 3). The whole-frame pass always runs; a frame
        never spends more than this plus its banked credit plus one pass (cold starts aside,
        counted apart). Raising it searches more tracks and scans the band more often, at more cost.
    credit_units: the most units a stream banks from frames that spent less than the budget, to
        spend on tracks at risk in a crowded frame (0..64; 3; 0: every frame on its own budget).
        Raising it lets a crowded frame search more of its tracks; the average stays the budget.
    scan_period_s: every band tile is looked at at least once this often, seconds (0.05..60; 1), as
        far as the budget allows (``run.json`` says when it did not): a new person far away is found
        within this time. Lowering it spends more of the budget on the band, less on the tracks.
    max_gap_s: a time step longer than this (or backwards) restarts the stream state (0.1..3600; 2):
        the tracks' crops and the tiles' ages no longer apply. Raise it for a slow frame rate.
    cold_start: on the first frame after a (re)start, scan the whole band (``far``'s cost) so far
        people are found at once; off: the rotation finds them within ``scan_period_s``.
    packed_height, packed_width: the packed input's size, px (multiples of 32, 128..1280; 384x640,
        one unit). Larger holds more crops per pass, at more cost per pass; the band's tiles are at
        most ``packed_width`` wide too.
    """

    budget_units: float = number(3.0, 1.0, 64.0)
    credit_units: float = number(3.0, 0.0, 64.0)
    scan_period_s: float = number(1.0, 0.05, 60.0)
    max_gap_s: float = number(2.0, 0.1, 3600.0)
    cold_start: bool = flag(True)
    packed_height: int = count(384, 128, 1280)
    packed_width: int = count(640, 128, 1280)

    def __post_init__(self) -> None:
        check_fields("detection.stream", self)
        for name in ("packed_height", "packed_width"):
            if getattr(self, name) % STRIDE:
                raise InputError(f"detection.stream.{name} must be a multiple of {STRIDE}, got {getattr(self, name)}")

    @property
    def packed_size(self) -> tuple[int, int]:
        """(height, width) of one packed input, px."""
        return self.packed_height, self.packed_width

    def to_dict(self) -> dict:
        return _fields(self)


@dataclass(frozen=True)
class DetectionConfig:
    """Where the pose network looks, section ``detection`` of the run's config (a bad value raises
    InputError naming ``detection.field``).

    ``far`` runs a pyramid of *levels*: the whole-frame pass, then one level per scale of
    ``level_scales``, each over the *band* of image rows where the people it is for can stand. A
    level at scale ``s`` is for people whose height in the image lies in
    ``[min_person_px / s, min_person_px / s_coarser)`` px (the whole-frame pass: at least
    ``min_person_px / its scale``). Those rows come from the calibration (the ground ``near_m``..
    ``far_m`` away) or, without a usable calibration, from a line fitted to the heights and foot
    rows of the people the coarser levels found.

    mode: ``fast`` (one pass), ``far`` (the levels) or ``stream`` (consecutive frames: the
        levels' tiles in rotation, :mod:`pedenv.detection.stream`; on a single image as ``far``).
    base_long_side: long side of the whole-frame pass's input, px (multiple of 32, 160..2048; 640);
        the short side follows the frame's aspect. Raising it finds smaller people, costs more.
    tile_width: longest side of one tile's input, px (multiple of 32, 160..4096; 3840); a level's
        band wider than this is cut into overlapping tiles (at most :data:`MAX_TILES`). Lowering it
        runs more, smaller passes (a model with a small fixed input).
    level_scales: scales of the far levels, ascending, each in [0.25, 4] (1 = native pixels), at
        most :data:`MAX_LEVELS` (8); (1, 2). A scale at or below the whole-frame pass's is skipped.
        Adding a finer scale finds smaller people and costs its square times the width of its rows.
    min_person_px: height in a level's input, px, of the smallest person that level is trusted to
        find (20..400; 80). Lowering it hands people to coarser, cheaper levels (fewer found).
    near_m, far_m: distances bounding every band, metres (0.5 <= near < far <= 1000; 5, 150).
        Raising ``far_m`` looks for people farther away (the finest level covers more rows).
    cascade: low-scoring small persons verified at a higher zoom (``far``, ``stream``): :class:`CascadeConfig`.
    stream: the ``stream`` mode's budget and rotation: :class:`StreamConfig`.
    """

    mode: str = choice("far", MODES)
    base_long_side: int = count(640, 160, 2048)
    tile_width: int = count(3840, 160, 4096)
    level_scales: tuple[float, ...] = (1.0, 2.0)
    min_person_px: float = number(80.0, 20.0, 400.0)
    near_m: float = number(5.0, 0.5, 1000.0)
    far_m: float = number(150.0, 0.5, 1000.0)
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

    @classmethod
    def named(cls, mode: str, **changes: Any) -> DetectionConfig:  # changes: field values
        """The config of a mode (``fast``, ``far`` or ``stream``) with some fields changed."""
        check_choice("detection mode", mode, MODES)
        return replace(cls(mode=mode), **changes)

    def to_dict(self) -> dict:
        return _fields(self)


@dataclass(frozen=True)
class RedetectConfig:
    """The track search: looking again for the live tracks a pass missed, around where the model
    predicts them (section ``redetect``; beyond the paper).

    In ``far`` and ``fast`` (``enabled``; the ``fused`` preset turns it on) every live track whose
    predicted box overlaps no detection is searched in a crop of its own, upscaled
    (:mod:`pedenv.detection.redetect`), each crop one more pass. ``stream`` always searches its
    tracks, in packed inputs within its budget (:mod:`pedenv.detection.stream`). Both keep the
    person found nearest the predicted box, within ``match_distance`` (:mod:`pedenv.detection.track_search`).

    enabled: run the re-detection in ``far`` and ``fast`` (``stream`` searches its tracks whatever it says).
    max_crops: at most this many crops per frame (0..64; 4), the tracks seen most often first.
        Raising it searches more tracks in a crowded frame, at one pass per crop.
    match_distance: a whole person found in a track's crop is that track when their box centre lies
        within this many predicted box heights of the predicted box's centre (0..2; 0.6). Raising it
        tolerates worse predictions (frames far apart, a turning walker), with more chance of taking
        a neighbour; 0 takes nobody.
    """

    enabled: bool = flag(False)
    max_crops: int = count(4, 0, 64)
    match_distance: float = number(0.6, 0.0, 2.0)

    def __post_init__(self) -> None:
        check_fields("redetect", self)


# ---------------------------------------------------------------------------------------------
# Constants of the algorithms (not settings), each with where its value comes from.

#: Overlap of neighbouring tiles, a fraction of the tile: more than the widest person the tiles are
#: for (geometry: a standing person is at most about 0.25 of the band's height wide), so each is
#: whole in one tile.
TILE_OVERLAP = 0.25
#: At most this many tiles per level; the level's scale is lowered to fit (cost bound: 12 tiles of
#: a 1600x900 frame at x2 are about ``far``'s measured 8 units).
MAX_TILES = 12
#: A finer level's detection taller than this in its input, px, is dropped: a fragment of someone
#: too large for that level (geometry: 480 px is 1.25 tiles of 384, a person whole only in a coarser pass).
MAX_PERSON_PX = 480.0
#: A level whose rows are unknown (no usable calibration, too few people to fit them) runs over the
#: whole image when that costs at most this many input megapixels (2.1: a 1600x900 frame at x1,
#: 8.5 units), else it is skipped; the finest level instead runs at a scale lowered to
#: WHOLE_IMAGE_FINEST_MPX (6: the frame at x2 is 23 units) so small people alone are still searched.
WHOLE_IMAGE_MAX_MPX = 2.1
WHOLE_IMAGE_FINEST_MPX = 6.0
#: The tallest and shortest person assumed when heights in px are turned into distances, metres
#: (anthropometry: 2.2 m is a tall adult with head room, 1.5 m a short one; children are found by
#: the levels' overlap).
TOP_M = 2.2
SHORT_PERSON_M = 1.5
#: Rows added above and below each calibrated band, px, for pitch noise (geometry: 16 px is about
#: 0.8 deg of pitch at a 1266 px focal length, KITTI's).
BAND_MARGIN_PX = 16
#: Fitting a level's rows without calibration: at least this many whole people scoring at least
#: FIT_MIN_SCORE found by the coarser levels; rows added above and below, a share of the level's
#: tallest person (measured on the real samples, docs/detection.md: 0.35 fits the dark KITTI frames).
FIT_MIN_PEOPLE = 3
FIT_MIN_SCORE = 0.35
FIT_MARGIN = 0.5
#: A finer level's detection scoring below SURE_SCORE is kept only when its 17 keypoint confidences
#: average at least PLAUSIBLE_KEYPOINT_CONF: a person, not a pole or a cone (measured on the real
#: samples: the precision of ``far``, 90 %).
SURE_SCORE = 0.5
PLAUSIBLE_KEYPOINT_CONF = 0.5
#: A camera tilted down more than this (degrees) is "looking down", up more than MAX_PITCH_UP_DEG sees
#: sky: the rows are then fitted, not calibrated (geometry of road cameras: within +-20 deg of level).
MAX_PITCH_DOWN_DEG = 20.0
MAX_PITCH_UP_DEG = 30.0
#: A detection within this many input px of an inner tile or crop edge counts as cut (half the
#: network's stride of 32: a box edge the network puts on the cut).
EDGE_MARGIN_PX = 16

#: The cascade's candidates (:mod:`pedenv.detection.cascade`): network score at least
#: CASCADE_MIN_SCORE, boxes CASCADE_MIN_HEIGHT_PX..CASCADE_MAX_HEIGHT_PX tall (image px), cropped
#: with CASCADE_MARGIN of their height on every side and zoomed so the person is CASCADE_PERSON_PX
#: tall (at most CASCADE_MAX_ZOOM times the image); kept when the zoomed person overlaps the
#: candidate by IoU CASCADE_MATCH_IOU, scores CASCADE_VERIFY_SCORE and averages
#: CASCADE_PLAUSIBLE_KEYPOINT_CONF keypoint confidence. Chosen on the real samples
#: (``benchmarks/cascade_real.py``: 40-80 px recall 53 -> 65 %, precision 94 -> 90 %).
CASCADE_MIN_SCORE = 0.05
CASCADE_MIN_HEIGHT_PX = 16.0
CASCADE_MAX_HEIGHT_PX = 160.0
CASCADE_PERSON_PX = 96.0
CASCADE_MAX_ZOOM = 3.5
CASCADE_MARGIN = 0.3
CASCADE_MATCH_IOU = 0.6
CASCADE_VERIFY_SCORE = 0.28
CASCADE_PLAUSIBLE_KEYPOINT_CONF = 0.6

#: ``stream``'s crops of the tracks (person px in the packed input, context as a share of the box
#: height, cut margin px), the usual ones, then the crowd's (a frame whose tracks at risk need more
#: packed inputs than it can pay): measured on MOT17 (``benchmarks/stream_crops.py``): about ten a
#: packed input and 92 % of the people found, or about twenty and 89 %.
TRACK_CROP = (96.0, 0.35, 16.0)
CROWD_CROP = (80.0, 0.25, 8.0)
#: In the crowd's style, neighbouring crops whose scales differ by at most this factor are joined
#: where that costs fewer input px (measured on MOT17 between 1.1, 1.25, 1.5 and 2).
MERGE_SCALE_RATIO = 1.25
#: A track is searched around its last detected box moved by its prediction's centre shift, unless
#: that shift exceeds this many of its heights (then its predicted box): measured on MOT17 and
#: vtest.avi, 0.5, 1 and 100 gave the same counts, 0 lost 14 and 13 people (docs/detection.md).
TRACK_MAX_SHIFT = 1.0
#: A finer level's band at most this many tile heights tall is scanned in one row of taller tiles:
#: measured on vtest.avi, 1 cost 6 tiles of 1.67 units per scan period instead of 3 of 1.75 and the
#: rotation ran past the budget.
BAND_ROW_STRETCH = 1.5
#: ``stream`` looks for tracks detected at least this often (1: a person the band rotation found
#: once is kept) whose predicted box no whole-frame detection overlaps by more than
#: STREAM_MISSED_IOU (the re-detection's value; measured on MOT17: recall 0.511 -> 0.523 with the
#: persons no track holds searched again too).
STREAM_MIN_HITS = 1
STREAM_MISSED_IOU = 0.3

#: The re-detection's crops (``far``/``fast``, :mod:`pedenv.detection.redetect`): the predicted box
#: with REDETECT_CROP_MARGIN of its height on every side, each side clamped to
#: REDETECT_MIN_CROP_PX..REDETECT_MAX_CROP_PX image px, upscaled by REDETECT_CROP_SCALE into an input
#: of at most REDETECT_MAX_INPUT_PX (one 640 unit); tracks with at least REDETECT_MIN_HITS hits (a
#: one-frame false positive is not chased) whose predicted box overlaps every detection by at most
#: REDETECT_MISSED_IOU. Measured on the KITTI samples (``benchmarks/redetect_real.py``).
REDETECT_CROP_MARGIN = 0.5
REDETECT_CROP_SCALE = 2.0
REDETECT_MIN_CROP_PX = 128
REDETECT_MAX_CROP_PX = 960
REDETECT_MAX_INPUT_PX = 640
REDETECT_MIN_HITS = 2
REDETECT_MISSED_IOU = 0.3
#: A person found in a track's crop is that track only when their box height lies within this
#: factor of the predicted box's (a neighbour of another size is refused; the tracker's own
#: ``max_height_ratio`` of the fused preset, 1.5).
MATCH_HEIGHT_RATIO = 1.5

#: The merge of passes (:mod:`pedenv.detection.merge`): two boxes with IoU above MERGE_IOU are one
#: person; a box lying MERGE_CONTAINMENT inside another is the same person when their keypoints
#: agree (OKS above MERGE_OKS over the keypoints both see with confidence MERGE_KEYPOINT_MIN_CONF):
#: the usual NMS IoU of YOLO-pose's evaluation (0.5) and COCO's keypoint similarity, measured on the
#: real samples (docs/detection.md: no person twice across tiles).
MERGE_IOU = 0.5
MERGE_CONTAINMENT = 0.7
MERGE_OKS = 0.3
MERGE_KEYPOINT_MIN_CONF = 0.3

#: Old names of settings (a saved ``config.json`` of ``detection.stream`` still loads).
RENAMED = {"mosaic_height": "packed_height", "mosaic_width": "packed_width"}
#: Settings that are no longer settings, with their fixed values: a saved ``config.json`` that holds
#: one of them at that value loads (it is dropped); another value is refused, naming the field.
RETIRED: dict[str, dict[str, Any]] = {
    "detection": {"tile_overlap": TILE_OVERLAP, "max_person_px": MAX_PERSON_PX,
                  "whole_image_max_mpx": WHOLE_IMAGE_MAX_MPX, "whole_image_finest_mpx": WHOLE_IMAGE_FINEST_MPX,
                  "top_m": TOP_M, "short_person_m": SHORT_PERSON_M, "band_margin_px": BAND_MARGIN_PX,
                  "fit_min_people": FIT_MIN_PEOPLE, "fit_min_score": FIT_MIN_SCORE, "fit_margin": FIT_MARGIN,
                  "sure_score": SURE_SCORE, "plausible_keypoint_conf": PLAUSIBLE_KEYPOINT_CONF,
                  "max_pitch_down_deg": MAX_PITCH_DOWN_DEG, "max_pitch_up_deg": MAX_PITCH_UP_DEG,
                  "max_tiles": MAX_TILES, "edge_margin_px": EDGE_MARGIN_PX},
    "detection.cascade": {"min_score": CASCADE_MIN_SCORE, "min_height_px": CASCADE_MIN_HEIGHT_PX,
                          "max_height_px": CASCADE_MAX_HEIGHT_PX, "person_px": CASCADE_PERSON_PX,
                          "max_zoom": CASCADE_MAX_ZOOM, "margin": CASCADE_MARGIN, "match_iou": CASCADE_MATCH_IOU,
                          "verify_score": CASCADE_VERIFY_SCORE,
                          "plausible_keypoint_conf": CASCADE_PLAUSIBLE_KEYPOINT_CONF},
    "detection.stream": {"track_person_px": TRACK_CROP[0], "track_margin": TRACK_CROP[1],
                         "track_edge_px": TRACK_CROP[2], "crowd_person_px": CROWD_CROP[0],
                         "crowd_margin": CROWD_CROP[1], "crowd_edge_px": CROWD_CROP[2], "search_untracked": True,
                         "merge_crops": True, "merge_scale_ratio": MERGE_SCALE_RATIO,
                         "track_max_shift": TRACK_MAX_SHIFT, "crop_min_width": 0.0,
                         "band_row_stretch": BAND_ROW_STRETCH, "track_min_hits": STREAM_MIN_HITS,
                         "missed_iou": STREAM_MISSED_IOU, "trim_mosaics": True},
    "redetect": {"crop_margin": REDETECT_CROP_MARGIN, "crop_scale": REDETECT_CROP_SCALE,
                 "min_crop_px": REDETECT_MIN_CROP_PX, "max_crop_px": REDETECT_MAX_CROP_PX,
                 "max_input_px": REDETECT_MAX_INPUT_PX, "missed_iou": REDETECT_MISSED_IOU,
                 "match_height_ratio": MATCH_HEIGHT_RATIO, "min_hits": REDETECT_MIN_HITS},
    "merge": {"iou": MERGE_IOU, "containment": MERGE_CONTAINMENT, "oks": MERGE_OKS,
              "keypoint_min_confidence": MERGE_KEYPOINT_MIN_CONF},
}


register_section("redetect", RedetectConfig, RETIRED["redetect"])
register_section("detection", DetectionConfig, RETIRED["detection"])
retire_section("merge", RETIRED["merge"])
