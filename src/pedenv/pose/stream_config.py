"""Settings of the ``stream`` detection and of the cascade for small people (validated).

Both sit inside :class:`pedenv.pose.tiling.DetectionConfig` (fields ``stream`` and
``cascade``); a bad value raises :class:`~pedenv.errors.InputError` naming
``detection.<section>.<field>``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, TypeVar

from pedenv.errors import InputError
from pedenv.validation import check_below, check_fields, count, flag, number

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

_T = TypeVar("_T", bound="DataclassInstance")


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
    times the image), packed several to one input (:mod:`pedenv.pose.mosaic`), and kept only
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
    """The ``stream`` detection over consecutive frames (:mod:`pedenv.pose.stream`).

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
        inputs (:func:`pedenv.pose.mosaic.merge_crops`): overlapping people are then seen
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
    mosaic_height, mosaic_width: the packed input's size, px (multiples of 32, 128..1280).
    trim_mosaics: a packed input is cut to the room its crops use (rounded up to 32 px; a model
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
    mosaic_height: int = count(384, 128, 1280)
    mosaic_width: int = count(640, 128, 1280)
    trim_mosaics: bool = flag(True)

    def __post_init__(self) -> None:
        check_fields("detection.stream", self)
        for kind in ("track", "crowd"):
            person, margin, edge = (getattr(self, f"{kind}_{f}") for f in ("person_px", "margin", "edge_px"))
            if edge >= max(margin * person, 1.0):
                raise InputError(f"detection.stream.{kind}_edge_px ({edge:g}) must be below the context "
                                 f"{kind}_margin * {kind}_person_px ({margin * person:g} px)")
        for name in ("mosaic_height", "mosaic_width"):
            if getattr(self, name) % 32:
                raise InputError(f"detection.stream.{name} must be a multiple of 32, got {getattr(self, name)}")

    @property
    def crop_styles(self) -> tuple[tuple[float, float, float], ...]:
        """(person px, margin, edge px) of the tracks' crops: the usual ones, then the crowd's."""
        return ((self.track_person_px, self.track_margin, self.track_edge_px),
                (self.crowd_person_px, self.crowd_margin, self.crowd_edge_px))

    @property
    def mosaic_size(self) -> tuple[int, int]:
        """(height, width) of one packed input, px."""
        return self.mosaic_height, self.mosaic_width

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}
