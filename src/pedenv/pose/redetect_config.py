"""Settings of the re-detection of missed tracks (:mod:`pedenv.pose.redetect`), section
``redetect`` of :class:`pedenv.config.Config` (which re-exports :class:`RedetectConfig`)."""

from __future__ import annotations

from dataclasses import dataclass

from pedenv.errors import InputError
from pedenv.validation import check_below, check_fields, count, flag, number


@dataclass(frozen=True)
class RedetectConfig:
    """Re-detection of missed tracks in high-resolution crops (``pedenv.pose.redetect``).

    Beyond the paper, off by default; the ``fused`` preset turns it on. Before the model
    takes a frame, every live track whose predicted box overlaps no detection of the main
    pass is searched for again: the pose network runs on an upscaled crop around the
    predicted box, and the person found there is merged with the frame's detections by the
    skeleton-aware NMS (``pedenv.pose.merge``), so nobody appears twice. Needs the ``onnx``
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
