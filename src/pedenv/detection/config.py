"""Every detection setting: the passes (``detection``), the stream and cascade inside it, the
re-detection of missed tracks (``redetect``) and the merge of passes (``merge``).

These are sections of the run's :class:`pedenv.config.Config` (registered here with
:func:`pedenv.config.register_section`, so the core's config imports nothing of detection);
a bad value raises :class:`~pedenv.errors.InputError` naming ``section.field``. The words
(pass, level, band, tile, unit, packed input, ...) are those of :mod:`pedenv.detection`.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any, TypeVar

from pedenv.config import register_section
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
    naming ``detection.<name>`` and its valid fields when a field is unknown)."""
    if isinstance(value, kind):
        return value
    if not isinstance(value, dict):
        raise InputError(f"detection.{name} must be an object of fields, got {type(value).__name__}")
    valid = {f.name for f in fields(kind)}
    unknown = sorted(str(k)[:40] for k in set(value) - valid)
    if unknown:
        raise InputError(f"unknown field(s) in detection.{name}: {', '.join(unknown[:5])}; "
                         f"valid: {', '.join(sorted(valid))}")
    return kind(**value)


@dataclass(frozen=True)
class CascadeConfig:
    """Persons the network scores below its threshold, verified at a higher zoom (``far``, ``stream``).

    A pass keeps persons scoring at least the backend's ``score_threshold``. Those scoring
    ``min_score`` up to it whose box is ``min_height_px``..``max_height_px`` tall become
    candidates: each is cropped with ``margin`` times its height of context on every side,
    scaled so the person is ``person_px`` tall in the network input (at most ``max_zoom``
    times the image), packed several to one input (:mod:`pedenv.detection.packing`), and kept only
    when that zoomed pass finds a whole person there (not cut by the crop's edges) overlapping
    the candidate's box by IoU at least ``match_iou``, scoring at least ``verify_score``, with
    a plausible skeleton (mean keypoint confidence at least ``plausible_keypoint_conf``).

    enabled: run the cascade.
    min_score: lowest network score of a candidate (0.01..0.5). Lowering it verifies more, at more cost.
    min_height_px, max_height_px: candidates' box heights, image px (8..400; min below max).
    person_px: a candidate's height in the zoomed input, px (32..384).
    max_zoom: at most this many input px per image px (1..8).
    margin: context on every side, a share of the candidate's height (0..1).
    match_iou: the zoomed person's box must overlap the candidate's by at least this IoU (0..1).
    verify_score: the zoomed person must score at least this (0..1). Raising it keeps fewer, surer ones.
    plausible_keypoint_conf: and average at least this keypoint confidence (0..1).
    max_units: at most this many network units (384x640 inputs) per frame for the cascade (1..16);
        the best-scoring candidates go first.

    The defaults were chosen on the real samples (``benchmarks/cascade_real.py``, docs/detection.md):
    ``far`` 40-80 px recall 53 -> 65 %, precision 94 -> 90 %, about 1 unit per image more.
    """

    enabled: bool = flag(True)
    min_score: float = number(0.05, 0.01, 0.5)
    min_height_px: float = number(16.0, 8.0, 400.0)
    max_height_px: float = number(160.0, 8.0, 400.0)
    person_px: float = number(96.0, 32.0, 384.0)
    max_zoom: float = number(3.5, 1.0, 8.0)
    margin: float = number(0.3, 0.0, 1.0)
    match_iou: float = number(0.6, 0.0, 1.0)
    verify_score: float = number(0.28, 0.0, 1.0)
    plausible_keypoint_conf: float = number(0.6, 0.0, 1.0)
    max_units: int = count(3, 1, 16)

    def __post_init__(self) -> None:
        check_fields("detection.cascade", self)
        check_below("detection.cascade.min_height_px", self.min_height_px,
                    "detection.cascade.max_height_px", self.max_height_px)

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True)
class StreamConfig:
    """The ``stream`` detection over consecutive frames (:mod:`pedenv.detection.stream`).

    Every frame: the whole-frame pass; the live tracks it missed, cropped around their
    predicted boxes and packed several to one input; the far band's tiles in rotation; the
    cascade's candidates in the free room of those inputs. Costs are in network units (one
    384x640 input).

    budget_units: network units per frame on average (1..64; at least one whole-frame pass). The
        whole-frame pass always runs; a frame never spends more than this plus its banked credit
        plus one pass (cold starts aside, counted apart).
    credit_units: the most units a stream banks from frames that spent less than the budget, to
        spend on tracks at risk in a crowded frame (0..64; 0: every frame on its own budget). A
        frame's overspend (a due tile) is owed back the same way, so the average stays at the budget.
    scan_period_s: every band tile is looked at at least once this often, seconds (0.05..60), as
        far as the budget allows (``run.json`` says when it did not): a new person far away is
        found within this time. Lowering it spends more of the budget on the band.
    track_person_px: a track's height in its crop's network input, px (32..384).
    track_margin: context around a predicted box, a share of its height on every side (0..2).
        Raising it tolerates worse predictions, with fewer crops per packed input.
    track_edge_px: a person found within this many input px of an inner edge of a track's crop is
        cut, not the track (0..64; below ``track_margin * track_person_px``, the context).
    crowd_person_px, crowd_margin, crowd_edge_px: the same for a crowded frame, whose tracks at
        risk need more packed inputs than the frame can pay with the crops above: smaller crops,
        about twenty to an input instead of about ten, each found a little less often
        (``benchmarks/stream_crops.py``: 89 % instead of 92 % of MOT17's people).
    search_untracked: the persons a frame found that no track holds (most score below what the
        tracker needs to start a track) are searched again in the next frame's packed inputs, after
        the tracks: zoomed, a weak person usually scores enough to become a track. MOT17 samples
        (``benchmarks/run_real.py``): recall 0.511 -> 0.523, false positives 121 -> 132.
    merge_crops: in the crowd's style (the frame cannot pay for the usual crops), join
        neighbouring tracks' crops into one where that costs fewer input px and packs in no more
        inputs (:func:`pedenv.detection.packing.merge_crops`): overlapping people are then seen
        together, not cut by each other's crop edges, and more fit in a packed input.
    merge_scale_ratio: only crops whose scales differ by at most this factor are joined (1..4);
        the joined crop takes the smaller scale, so its shorter person is up to this much smaller
        in the input than ``crowd_person_px``. Chosen on the MOT17 samples (1.1, 1.25, 1.5, 2).
    track_max_shift: a track is searched around the box it was last detected with, moved by the
        centre shift of its predicted box (the tracker's per-edge velocities distort the box's
        size), and its crop covers the last detection too; a shift longer than this many of its
        heights means the remembered box is not that track's (ids reused between frames, as
        ``evaluate-detections``' stand-in tracks are, or a wrong association): its predicted box
        is searched as it is (0..100; 0: always the predicted box). MOT17 samples and vtest.avi
        (docs/detection.md): 0.5, 1 and 100 gave the same counts, 0 lost 14 and 13 people.
    crop_min_width: a track's crop is cut as if its box were at least this share of its height wide,
        about the box's centre (0..2; 0: the box's own width). A walker's box widens and narrows
        within a stride (legs together, legs apart) and a new track has no motion yet: a crop
        around a narrow box cut the person it looked for by its inner edge. Off by default: 0.6
        found 94.9 -> 95.8 % of far's people on vtest.avi but cost the MOT17 samples 0.523 -> 0.516
        (``benchmarks/stream_misses.py``, docs/detection.md).
    band_row_stretch: a finer level's band at most this many tile heights tall is scanned in one
        row of taller tiles instead of two rows of square ones (1..2; 1: never). The same image
        rows for fewer input px: on vtest.avi the x2 band, 6 px taller than a tile, cost 6 tiles of
        1.67 units per scan period instead of 3 of 1.75, and the rotation ran past the budget.
    track_min_hits: only tracks detected at least this many times are looked for (1..1000). A new
        track (one hit) is looked for at once: a person the band rotation found once is kept.
    missed_iou: a track whose predicted box overlaps no whole-frame detection by more than this
        IoU (0..1) is looked for in a crop.
    max_gap_s: a time step longer than this (or backwards) restarts the stream state (0.1..3600):
        tracks' crops and tile ages no longer apply.
    cold_start: on the first frame after a (re)start, scan the whole band (``far``'s cost) so
        far people are found at once; off: the rotation finds them within ``scan_period_s``.
    packed_height, packed_width: the packed input's size, px (multiples of 32, 128..1280).
    trim_packed: a packed input is cut to the room its crops use (rounded up to 32 px; a model
        with a dynamic input, on the CPU: a GPU pass costs about the same whatever its size, and
        each new input shape there costs a session): three far tracks cost what their crops
        cover, not a whole packed input. The plan still reserves whole packed inputs; what a frame does not spend
        goes to the credit bank, then to the band's tiles.
    """

    budget_units: float = number(3.0, 1.0, 64.0)
    credit_units: float = number(3.0, 0.0, 64.0)
    scan_period_s: float = number(1.0, 0.05, 60.0)
    track_person_px: float = number(96.0, 32.0, 384.0)
    track_margin: float = number(0.35, 0.0, 2.0)
    track_edge_px: float = number(16.0, 0.0, 64.0)
    crowd_person_px: float = number(80.0, 32.0, 384.0)
    crowd_margin: float = number(0.25, 0.0, 2.0)
    crowd_edge_px: float = number(8.0, 0.0, 64.0)
    search_untracked: bool = flag(True)
    merge_crops: bool = flag(True)
    merge_scale_ratio: float = number(1.25, 1.0, 4.0)
    track_max_shift: float = number(1.0, 0.0, 100.0)
    crop_min_width: float = number(0.0, 0.0, 2.0)
    band_row_stretch: float = number(1.5, 1.0, 2.0)
    track_min_hits: int = count(1, 1, 1000)
    missed_iou: float = number(0.3, 0.0, 1.0)
    max_gap_s: float = number(2.0, 0.1, 3600.0)
    cold_start: bool = flag(True)
    packed_height: int = count(384, 128, 1280)
    packed_width: int = count(640, 128, 1280)
    trim_packed: bool = flag(True)

    def __post_init__(self) -> None:
        check_fields("detection.stream", self)
        for kind in ("track", "crowd"):
            person, margin, edge = (getattr(self, f"{kind}_{f}") for f in ("person_px", "margin", "edge_px"))
            if edge >= max(margin * person, 1.0):
                raise InputError(f"detection.stream.{kind}_edge_px ({edge:g}) must be below the context "
                                 f"{kind}_margin * {kind}_person_px ({margin * person:g} px)")
        for name in ("packed_height", "packed_width"):
            if getattr(self, name) % 32:
                raise InputError(f"detection.stream.{name} must be a multiple of 32, got {getattr(self, name)}")

    @property
    def crop_styles(self) -> tuple[tuple[float, float, float], ...]:
        """(person px, margin, edge px) of the tracks' crops: the usual ones, then the crowd's."""
        return ((self.track_person_px, self.track_margin, self.track_edge_px),
                (self.crowd_person_px, self.crowd_margin, self.crowd_edge_px))

    @property
    def packed_size(self) -> tuple[int, int]:
        """(height, width) of one packed input, px."""
        return self.packed_height, self.packed_width

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


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
        levels' tiles in rotation, :mod:`pedenv.detection.stream`; on a single image as ``far``).
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



@dataclass(frozen=True)
class RedetectConfig:
    """Re-detection of missed tracks in high-resolution crops (``pedenv.detection.redetect``).

    Beyond the paper, off by default; the ``fused`` preset turns it on. Before the model
    takes a frame, every live track whose predicted box overlaps no detection of the main
    pass is searched for again: the pose network runs on an upscaled crop around the
    predicted box, and the person found there is merged with the frame's detections by the
    skeleton-aware NMS (``pedenv.detection.merge``), so nobody appears twice. Needs the ``onnx``
    backend; each crop is one extra network pass.

    enabled: run the re-detection.
    crop_margin: context added on every side of the predicted box, as a share of its height
        (0..2). Raising it tolerates worse predictions, with fewer input pixels per person.
    crop_scale: crop pixels -> network input pixels (0.25..4; 2 = twice the native size),
        lowered where the input would exceed ``max_input_px``. Raising it finds smaller people.
    min_crop_px, max_crop_px: each side of the crop region is clamped to this range, image
        pixels (32..4096); a tiny box still gets context, a huge one a bounded crop.
    max_input_px: the longest side of a crop's network input, pixels (multiple of 32,
        64..1280). Raising it keeps the scale for larger people, at more cost per crop.
    max_crops: at most this many crops per frame (0..64); the tracks seen most often go
        first. Bounds the extra cost per frame.
    missed_iou: a track whose predicted box overlaps every detection by at most this IoU
        (0..1) counts as missed. Raising it searches more tracks.
    match_distance: a whole person found in a crop re-detects the track when their box
        centre lies within this many predicted box heights of the predicted box's centre
        (0..2); the nearest is kept, the rest of the crop ignored (people the main pass found
        are merged away in any case). Raising it tolerates worse predictions (frames far
        apart, a turning walker), with more chance of taking a neighbour.
    match_height_ratio: and when their box height lies within this factor of the predicted
        box's (1..5). Lowering it refuses more re-detections of another size.
    min_hits: only tracks detected at least this many times are searched (1..1000), so a
        one-frame false positive is not chased.
    """

    enabled: bool = flag(False)
    crop_margin: float = number(0.5, 0.0, 2.0)
    crop_scale: float = number(2.0, 0.25, 4.0)
    min_crop_px: int = count(128, 32, 4096)
    max_crop_px: int = count(960, 32, 4096)
    max_input_px: int = count(640, 64, 1280)
    max_crops: int = count(4, 0, 64)
    missed_iou: float = number(0.3, 0.0, 1.0)
    match_distance: float = number(0.6, 0.0, 2.0)
    match_height_ratio: float = number(1.5, 1.0, 5.0)
    min_hits: int = count(2, 1, 1000)

    def __post_init__(self) -> None:
        check_fields("redetect", self)
        check_below("redetect.min_crop_px", self.min_crop_px, "redetect.max_crop_px", self.max_crop_px, equal_ok=True)
        if self.max_input_px % 32:
            raise InputError(f"redetect.max_input_px must be a multiple of 32, got {self.max_input_px}")


@dataclass(frozen=True)
class MergeConfig:
    """Thresholds of the skeleton-aware NMS, section ``merge`` of :class:`pedenv.config.Config`
    (validated by :mod:`pedenv.validation`; a bad value raises InputError naming ``merge.field``).

    iou: two boxes with IoU above this are one person (0..1; default 0.5).
    containment: a box whose area lies this fraction inside another's (0..1; 0.7) is the
        same person when the keypoints also agree.
    oks: keypoint similarity above which nested boxes are one person (0..1; 0.3).
    keypoint_min_confidence: keypoints below this confidence are not compared (0..1; 0.3).
    """

    iou: float = number(0.5, 0.0, 1.0)
    containment: float = number(0.7, 0.0, 1.0)
    oks: float = number(0.3, 0.0, 1.0)
    keypoint_min_confidence: float = number(0.3, 0.0, 1.0)

    def __post_init__(self) -> None:
        check_fields("merge", self)




register_section("redetect", RedetectConfig)
register_section("detection", DetectionConfig)
register_section("merge", MergeConfig)
