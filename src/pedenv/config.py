"""One typed configuration object; every constant of the paper is a named, validated value.

Defaults are the paper's (Holzbock et al., Sections III-B and III-C) where it gives one.
``Config.to_dict()`` is saved next to every result so a run can be repeated.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from pedenv.errors import InputError, read_text


def _check_range(name: str, value, low=None, high=None, *, low_open=False, high_open=False) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{name} must be a number, got {value!r}")
    bad_low = low is not None and (value <= low if low_open else value < low)
    bad_high = high is not None and (value >= high if high_open else value > high)
    if bad_low or bad_high:
        lo = "" if low is None else ("(" if low_open else "[") + f"{low}"
        hi = "" if high is None else f"{high}" + (")" if high_open else "]")
        raise InputError(f"{name} must be in {lo or '(-inf'}, {hi or 'inf)'}, got {value}")


def _check_choice(name: str, value, choices) -> None:
    if value not in choices:
        raise InputError(f"{name} must be one of {', '.join(map(repr, choices))}, got {value!r}")


@dataclass(frozen=True)
class TrackingConfig:
    """Association of skeletons in the image (Sec. III-B).

    giou_threshold: a detection and a track overlap when their generalized IoU is above
        this (in [-1, 1)). The authors' public code uses -0.3. Raising it makes the
        tracker start new tracks more readily; lowering it lets distant boxes be joined.
    max_misses: a track is dropped after this many consecutive frames without a
        detection (the paper: 3). Raising it keeps tracks alive through occlusions.
    yaw_compensation: shift the tracks' pixels by the ego's yaw change before
        association (Eq. 1). Turning it off is an ablation.
    max_height_ratio: beyond the paper, off (0) by default: a detection and a track whose
        box heights differ by more than this factor cannot be associated, so a small
        distant person is not joined to the stale box of a near one. Lowering it (towards
        1) splits more tracks; the ``fused`` preset uses 1.5.
    predict_motion: beyond the paper, off by default: move each track's box by its
        smoothed image velocity before association (as SORT does), so people who cross
        each other in the image keep their ids. The ``fused`` preset turns it on.
    low_score_threshold: beyond the paper, off (0) by default: a two-band association as
        in ByteTrack. Detections scoring below ``start_score_threshold`` but at least this
        may only continue a track, never start one; detections below it are ignored. Both
        bands go into one assignment, the low band paying ``low_score_cost`` extra, so a
        sure detection still wins a track over a weak one, but a weak detection of a
        half-hidden neighbour keeps a sure one from taking the neighbour's track (KITTI
        0016 frame 7; ByteTrack's strictly sequential stages swap those two). Needs a pose
        backend that reports them (``OnnxPose(score_threshold=0.1)``). Lowering it keeps
        more occluded people's tracks alive, and lets more clutter continue a track.
        The ``fused`` preset uses 0.1.
    start_score_threshold: with the two-stage association on, only detections scoring at
        least this start a track or are associated in the first stage (0.25, the pose
        backends' usual threshold). Raising it starts fewer, surer tracks.
    low_score_cost: what a low-band detection adds to the association cost (0..2; GIoU
        lies in [-1, 1]). Raising it makes the low band take only tracks no sure detection
        overlaps.
    ground_gate: beyond the paper, off (0) by default: each track's Kalman-predicted ground
        position is projected into the image; a detection whose box foot point lies
        farther than this squared Mahalanobis distance (2 dof, pixels) from it cannot be
        associated with the track, and nearer ones pay ``ground_cost_weight`` times the
        distance over the gate on top of the negative GIoU. Keeps two people side by side
        or crossing apart when their boxes overlap. The projected covariance is generous
        (it holds the road's height and a range bias, :mod:`pedenv.tracking.projection`),
        so the gate can be tight: the ``fused`` preset uses 4 (5.9 id switches per 100
        matches on the first 6 s of the seed-0 terrain scenes, 7.3 with 16). Lowering it splits tracks
        more readily.
    ground_cost_weight: weight of the projected-prediction distance in the association
        cost (0..10). Raising it trusts the Kalman prediction more than the box overlap.
    memory_s: beyond the paper, off (0) by default: a track missed ``max_misses`` times is
        not dropped but remembered this many seconds with its Kalman state; a new
        detection no track took in the image whose foot point lies within ``memory_gate``
        (squared Mahalanobis distance, 2 dof) of a remembered (or just missed) track's
        predicted ground position gets that track's id back. Raising it bridges longer
        occlusions, with more chance of handing an old id to someone else. The ``fused``
        preset uses 2 s. Needs the camera (the model passes it).
    memory_gate: the squared Mahalanobis gate of re-identification after an occlusion
        (the ``fused`` preset: 9.2, the 99 % quantile). Raising it re-identifies more.
    camera_check: the ground gate and the memory trust the camera only while its
        projections agree with the image: in a frame where more than this fraction of the
        unambiguous box matches (a track and a detection each other's best, IoU >= 0.5;
        at least 3 of them) fall outside the ground gate, both abstain and the boxes decide
        (0..1; 1 never abstains). A wrong or guessed calibration otherwise splits every
        track (MOT17 with a guessed camera: 244 id switches in 39 frames). With a true
        camera about one match in seven lies outside the 86 % gate by chance, so more than
        a third (0.34) is already a sign; at 0.5 a recording whose projections disagree
        with the image in 2 of 4 matches kept the gate, and a low-score sliver took a
        person's id. The seeded synthetic figures and the real KITTI and MOT17 runs are the
        same at 0.34 and 0.5.
    """

    giou_threshold: float = -0.3
    max_misses: int = 3
    yaw_compensation: bool = True
    max_height_ratio: float = 0.0
    predict_motion: bool = False
    low_score_threshold: float = 0.0
    start_score_threshold: float = 0.25
    low_score_cost: float = 0.5
    ground_gate: float = 0.0
    ground_cost_weight: float = 1.0
    memory_s: float = 0.0
    memory_gate: float = 9.21
    camera_check: float = 0.34

    @property
    def pose_score_threshold(self) -> float | None:
        """The person score threshold a pose network should run at so the low band reaches
        the tracker: ``low_score_threshold`` while the two-band association is on, else
        None (the backend's own threshold; the paper's input stays as it was)."""
        return self.low_score_threshold if self.low_score_threshold > 0 else None

    def __post_init__(self) -> None:
        _check_range("tracking.giou_threshold", self.giou_threshold, -1.0, 1.0, high_open=True)
        if self.max_height_ratio != 0.0:
            _check_range("tracking.max_height_ratio (0 = off)", self.max_height_ratio, 1.0, low_open=True)
        if not isinstance(self.max_misses, int) or isinstance(self.max_misses, bool) or self.max_misses < 1:
            raise InputError(f"tracking.max_misses must be an integer >= 1, got {self.max_misses!r}")
        _check_range("tracking.start_score_threshold", self.start_score_threshold, 0.0, 1.0)
        if self.low_score_threshold != 0.0:
            _check_range("tracking.low_score_threshold (0 = off)", self.low_score_threshold, 0.0,
                         self.start_score_threshold, low_open=True)
        _check_range("tracking.low_score_cost", self.low_score_cost, 0.0, 2.0)
        _check_range("tracking.ground_gate (0 = off)", self.ground_gate, 0.0, 1000.0)
        _check_range("tracking.ground_cost_weight", self.ground_cost_weight, 0.0, 10.0)
        _check_range("tracking.memory_s (0 = off)", self.memory_s, 0.0, 60.0)
        _check_range("tracking.camera_check", self.camera_check, 0.0, 1.0)
        _check_range("tracking.memory_gate", self.memory_gate, 0.0, 1000.0, low_open=True)


INITIAL_ESTIMATES = ("all-keypoints", "midpoint")


@dataclass(frozen=True)
class PaperConfig:
    """The paper's position method (Sec. III-C, Algorithm 1): two-frame ray intersection
    and height refinement (``pedenv.localization.paper``).

    low_confidence_fraction: share of keypoints with the lowest confidence left out of
        the initial estimate (the paper: 0.3). Raising it trusts fewer, surer keypoints.
    initial_estimate: ``all-keypoints`` (the paper) or ``midpoint`` (ablation of
        Sec. IV-D: only the skeleton's midpoint, the centre of its box).
    refine: run the distance and direction refinement (ablation: off).
    person_height_m: the assumed body height re-projected in the refinement (1.7 m).
        Raising it moves every refined pedestrian farther away.
    refinement_steps: number of refinement iterations (the paper: 15).
    refinement_lambda_offset: ``c`` in ``lambda = r + c`` for step ``r`` = 1..steps (the
        paper: 5). Each step scales the distance by ``1 + (h_est / h_orig - 1) / lambda``;
        raising ``c`` makes the refinement move less from the initial estimate.
    min_parallax_rad: rays closer to parallel than this angle do not intersect; the
        position then falls back to the height-based distance.
    max_distance_m: triangulated keypoints farther than this from the camera are
        discarded as degenerate, and no position is reported farther than this
        (horizontally) from the camera: the model clamps it as ``fused.max_range_m``.
    measurement_std_m: standard deviation of one position measurement per axis (the
        Kalman filter's R), as a fraction of the distance plus this floor; the paper
        gives none (tuned on the built-in scenes).
    measurement_std_rel: relative part of the measurement noise (per metre of distance).
    """

    low_confidence_fraction: float = 0.3
    initial_estimate: str = "all-keypoints"
    refine: bool = True
    person_height_m: float = 1.7
    refinement_steps: int = 15
    refinement_lambda_offset: float = 5.0
    min_parallax_rad: float = 1e-6
    max_distance_m: float = 500.0
    measurement_std_m: float = 0.5
    measurement_std_rel: float = 0.1

    def __post_init__(self) -> None:
        _check_range("paper.low_confidence_fraction", self.low_confidence_fraction, 0.0, 1.0, high_open=True)
        _check_choice("paper.initial_estimate", self.initial_estimate, INITIAL_ESTIMATES)
        _check_range("paper.person_height_m", self.person_height_m, 0.3, 2.5)
        if not isinstance(self.refinement_steps, int) or self.refinement_steps < 0:
            raise InputError(f"paper.refinement_steps must be an integer >= 0, got {self.refinement_steps!r}")
        _check_range("paper.refinement_lambda_offset", self.refinement_lambda_offset, 0.0, low_open=True)
        _check_range("paper.min_parallax_rad", self.min_parallax_rad, 0.0, 0.1)
        _check_range("paper.max_distance_m", self.max_distance_m, 1.0)
        _check_range("paper.measurement_std_m", self.measurement_std_m, 0.0, low_open=True)
        _check_range("paper.measurement_std_rel", self.measurement_std_rel, 0.0)




@dataclass(frozen=True)
class KalmanConfig:
    """Constant-velocity Kalman filter on the ground-plane position (Sec. III-C).

    The paper names the filter but not its noise; these defaults were tuned on the
    built-in scenes.

    enabled: filter the positions (off: raw per-frame estimates).
    acceleration_std_mps2: white-noise acceleration of a pedestrian (Q via filterpy's
        ``Q_discrete_white_noise``). Raising it follows turns faster, smooths less.
    The measurement noise R comes with each measurement from the position method.

    initial_velocity_std_mps: prior spread of a new track's velocity.
    restart_gate: beyond the paper, off (0) by default: a measurement whose squared
        Mahalanobis distance from the track's prediction exceeds this restarts the
        track's filter at the measurement (the track has switched to another person).
        Lowering it restarts more readily; the ``fused`` preset uses 25.
    """

    enabled: bool = True
    acceleration_std_mps2: float = 1.0
    initial_velocity_std_mps: float = 2.0
    restart_gate: float = 0.0

    def __post_init__(self) -> None:
        _check_range("kalman.acceleration_std_mps2", self.acceleration_std_mps2, 0.0, low_open=True)
        _check_range("kalman.initial_velocity_std_mps", self.initial_velocity_std_mps, 0.0, low_open=True)
        _check_range("kalman.restart_gate (0 = off)", self.restart_gate, 0.0)


FUSED_CUES = ("ground", "triangulation", "height")


def _check_count(name: str, value, low: int) -> None:
    if not isinstance(value, int) or isinstance(value, bool) or value < low:
        raise InputError(f"{name} must be an integer >= {low}, got {value!r}")


@dataclass(frozen=True)
class FusedConfig:
    """The ``fused`` position method (``pedenv.localization.fused``): three cues fused with their variances.

    Not in the paper; defaults are anthropometric tables, the synthetic scenes' ranges
    and values tuned on the built-in scenes. Every variance below is a 1-sigma spread.

    cues: which cues run, any of ``ground``, ``triangulation``, ``height``. Leaving one
        out is an ablation; the others carry the estimate.
    person_height_mean_m, person_height_std_m: prior of adult body height (1.72 m, 0.09 m,
        about 5 %). Raising the mean moves every height-based estimate farther away;
        raising the spread makes the height cue count less against the others.
    keypoint_pixel_std: pixel noise of one keypoint (u and v): the prior of each
        skeleton's own noise, which is measured from its left/right keypoint pairs
        (weight 0.1 pair) and used by every cue. Raising it widens the cues' variances
        where a skeleton shows little evidence of its own noise.
    min_keypoint_confidence: keypoints below this confidence are not used by any cue
        (pose networks still guess unseen keypoints, with low confidence). Raising it
        uses fewer, surer keypoints.
    ankle_height_std_m: how far an ankle may sit above its resting height (feet lifting
        in the swing phase). Raising it widens the ground cue.
    road_height_std_m: the road under a pedestrian may lie this far off the vehicle's
        plane even nearby (kerbs, camber, suspension). Raising it widens the ground cue.
    road_curvature_std_per_m: spread of the road's curvature (1/m); the road under a
        pedestrian ``r`` metres away lies about ``0.5 * curvature * r^2`` off the
        vehicle's plane. Raising it makes the ground cue fade sooner with distance.
    ground_max_distance_m: the ground cue declines beyond this horizontal distance (a
        vehicle-mounted camera: its pitch and height over the road change as it drives).
        A ``static`` camera (``Camera.mount``) has no such limit, see below.
    static_ground_max_relative_std: a ``static`` camera's ground cue declines where the
        foot point's own spread along the ray (its pixel noise and the ankle's lift, carried
        through the ray's cut with the ground) exceeds this share of the range: there the
        ray grazes the ground, the linearized cut no longer holds and the height prior is
        sharper. Raising it uses the ground cue farther out.
    static_ground_height_std_m: the ground's unevenness under a pedestrian against a static
        camera's calibrated plane (paving, gutters), metres, per person; a static camera has
        no pitch or height noise, so this replaces ``road_height_std_m`` and
        ``road_curvature_std_per_m``. Raising it widens its ground cue along the ray.
    history_length: past observations of a track kept for triangulation. Raising it
        gives more baseline when driving slowly, at more cost per pedestrian; older rays
        add little (a walker's drift grows with their age): on the built-in terrain
        scenes 6 gave the exact-skeleton error of 10 and a lower detector-model one
        (7.3 vs 7.7 %), at 6/10 of the triangulation's cost.
    min_baseline_m: a past camera centre closer than this to the current one gives no
        ray for triangulation (the ego stands still).
    min_parallax_rad: rays closer to parallel than this are left out of triangulation;
        if none is left the cue declines.
    pedestrian_speed_std_mps: how fast a pedestrian may have moved since a past
        observation; widens old rays so a walker does not bias triangulation.
    outlier_sigma: a ray whose normalized miss distance exceeds this is dropped from
        triangulation. Raising it keeps more rays.
    gate_probability: a cue whose disagreement with the other cues exceeds this
        chi-square quantile (2 dof) is dropped before fusion. Raising it keeps more cues.
    lateral_std_m: spread of the ground point across the ray beyond pixel noise (body
        lean, where the feet stand against the body's centre, the keypoints' placement).
        Raising it widens the covariance across the ray. 0.05 m: the sideways errors of the
        fused method on the real KITTI and nuScenes persons (RMS 0.051 m at 9-16 m, where the
        measured keypoint jitter, under 1 px, adds about 0.01 m); the fused covariance
        across the ray is floored at the sharpest cue's, since all cues share this error.
        It repeats over a gait cycle and for the person, so it is the per-person part of
        each cue's covariance: the Kalman filter does not average it away.
    stance_std_m: spread of a standing foot's ground point about the body's (per axis, metres):
        a walker's stance foot lies up to half a step (about 0.2 H) ahead of or behind the
        body, so 0.2 m along the unknown walking direction, about 0.14 m each way; the midpoint
        of two standing feet counts half of it. It changes with every step (frame-to-frame).
        Raising it makes the ground cue count less across the ray, where it was the cue
        whose sideways errors were 2.8x (0-10 m) its variance on the terrain scenes without it.
    keypoint_span_scale: the pose source's eyes-to-ankles span as a share of the span in the
        anatomical table of the height cue (eyes 0.933, ankles 0.046 of body height, upright).
        1.0 takes the table as it is; the real YOLO11n-pose spans 0.823 of the true height on
        KITTI (0.93 of the table), so the height cue puts its people about 7 % too far unless
        this is lowered. Lowering it moves height-cue estimates nearer.
    keypoint_span_std: per-person spread of that span against body height (posture: a
        walker's bent knees and tilted head; where the network puts the keypoints), relative;
        repeats for the same person, so it adds to the height cue's per-person covariance
        with the height spread. Measured on the real network: 0.017 (KITTI, 10 persons).
    max_range_m: the farthest horizontal range from the camera the method reports, metres
        (200 m: a 1.7 m person is then about 11 px tall in a 1600 px wide 64.5 deg image,
        below what a pose network finds). A skeleton placed farther (a tiny false
        positive went to 243 km) is clamped to this range along its bearing and its
        covariance along the ray widened by ``max_range_m**2`` (its range is unknown);
        its ``sources`` ends with ``;clamped``. Raising it lets farther estimates through.

    Each cue splits its covariance into the part new every frame (pixel noise, gait) and
    the part that repeats for the same person (height prior, road under them, a walker's
    drift); the model filters the first and adds the second to what it reports.
    """

    cues: tuple[str, ...] = FUSED_CUES
    person_height_mean_m: float = 1.72
    person_height_std_m: float = 0.09
    keypoint_pixel_std: float = 3.0
    min_keypoint_confidence: float = 0.3
    ankle_height_std_m: float = 0.04
    road_height_std_m: float = 0.08
    road_curvature_std_per_m: float = 0.008
    ground_max_distance_m: float = 20.0
    static_ground_max_relative_std: float = 0.2
    static_ground_height_std_m: float = 0.02
    history_length: int = 6
    min_baseline_m: float = 0.3
    min_parallax_rad: float = 0.01
    pedestrian_speed_std_mps: float = 0.8
    outlier_sigma: float = 3.0
    gate_probability: float = 0.999
    lateral_std_m: float = 0.05
    stance_std_m: float = 0.14
    keypoint_span_scale: float = 1.0
    keypoint_span_std: float = 0.017
    max_range_m: float = 200.0

    def __post_init__(self) -> None:
        cues = tuple(self.cues) if not isinstance(self.cues, str) else tuple(c for c in self.cues.split(",") if c)
        if not cues:
            raise InputError(f"fused.cues must name at least one of {', '.join(FUSED_CUES)}")
        for cue in cues:
            _check_choice("fused.cues entry", cue, FUSED_CUES)
        object.__setattr__(self, "cues", cues)
        _check_range("fused.person_height_mean_m", self.person_height_mean_m, 0.5, 2.5)
        _check_range("fused.person_height_std_m", self.person_height_std_m, 0.0, 0.5, low_open=True)
        _check_range("fused.keypoint_pixel_std", self.keypoint_pixel_std, 0.0, 100.0, low_open=True)
        _check_range("fused.min_keypoint_confidence", self.min_keypoint_confidence, 0.0, 1.0, high_open=True)
        _check_range("fused.ankle_height_std_m", self.ankle_height_std_m, 0.0, 1.0)
        _check_range("fused.road_height_std_m", self.road_height_std_m, 0.0, 2.0)
        _check_range("fused.road_curvature_std_per_m", self.road_curvature_std_per_m, 0.0, 0.1)
        _check_range("fused.ground_max_distance_m", self.ground_max_distance_m, 1.0, 1000.0)
        _check_range("fused.static_ground_max_relative_std", self.static_ground_max_relative_std, 0.0, 1.0,
                     low_open=True)
        _check_range("fused.static_ground_height_std_m", self.static_ground_height_std_m, 0.0, 1.0)
        _check_count("fused.history_length", self.history_length, 1)
        _check_range("fused.min_baseline_m", self.min_baseline_m, 0.0, 100.0)
        _check_range("fused.min_parallax_rad", self.min_parallax_rad, 0.0, 0.5)
        _check_range("fused.pedestrian_speed_std_mps", self.pedestrian_speed_std_mps, 0.0, 10.0)
        _check_range("fused.outlier_sigma", self.outlier_sigma, 0.0, low_open=True)
        _check_range("fused.gate_probability", self.gate_probability, 0.0, 1.0, low_open=True, high_open=True)
        _check_range("fused.lateral_std_m", self.lateral_std_m, 0.0, 5.0)
        _check_range("fused.stance_std_m", self.stance_std_m, 0.0, 2.0)
        _check_range("fused.keypoint_span_scale", self.keypoint_span_scale, 0.5, 1.5)
        _check_range("fused.keypoint_span_std", self.keypoint_span_std, 0.0, 0.5)
        _check_range("fused.max_range_m", self.max_range_m, 5.0, 10000.0)


#: The position method of ``Config()`` and of every command without ``--method``: the
#: most accurate one (``paper`` reproduces the paper's figures).
DEFAULT_METHOD = "fused"

#: Per method, the fields whose defaults differ from the section classes' own defaults
#: (which are the paper's values). ``fused`` turns on the tracker's height-ratio rule,
#: low-score second pass, motion prediction, ground gate and track memory, and the
#: filter's restart gate, and the re-detection of missed tracks in crops (onnx backend,
#: :mod:`pedenv.pose.redetect`) (on the golden ``terrain2/fused/detector-model`` case 75 identity
#: switches with them, 200 without).
METHOD_PRESETS: dict[str, dict[str, dict]] = {
    "paper": {},
    "fused": {"tracking": {"max_height_ratio": 1.5, "predict_motion": True, "low_score_threshold": 0.1,
                           "ground_gate": 4.0, "memory_s": 2.0},
              "kalman": {"restart_gate": 25.0}, "redetect": {"enabled": True}},
}


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

    enabled: bool = False
    crop_margin: float = 0.5
    crop_scale: float = 2.0
    min_crop_px: int = 128
    max_crop_px: int = 960
    max_input_px: int = 640
    max_crops: int = 4
    missed_iou: float = 0.3
    match_distance: float = 0.6
    match_height_ratio: float = 1.5
    min_hits: int = 2

    def __post_init__(self) -> None:
        if not isinstance(self.enabled, bool):
            raise InputError(f"redetect.enabled must be true or false, got {self.enabled!r}")
        _check_range("redetect.crop_margin", self.crop_margin, 0.0, 2.0)
        _check_range("redetect.crop_scale", self.crop_scale, 0.25, 4.0)
        for name, low, high in (("min_crop_px", 32, 4096), ("max_crop_px", 32, 4096), ("max_input_px", 64, 1280),
                                ("max_crops", 0, 64), ("min_hits", 1, 1000)):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
                raise InputError(f"redetect.{name} must be an integer in [{low}, {high}], got {value!r}")
        if self.min_crop_px > self.max_crop_px:
            raise InputError(f"redetect.min_crop_px ({self.min_crop_px}) must not exceed "
                             f"redetect.max_crop_px ({self.max_crop_px})")
        if self.max_input_px % 32:
            raise InputError(f"redetect.max_input_px must be a multiple of 32, got {self.max_input_px}")
        _check_range("redetect.missed_iou", self.missed_iou, 0.0, 1.0)
        _check_range("redetect.match_distance", self.match_distance, 0.0, 2.0)
        _check_range("redetect.match_height_ratio", self.match_height_ratio, 1.0, 5.0)


@dataclass(frozen=True)
class Config:
    """Everything the environment model needs besides the data.

    method: the position method, a name of :data:`pedenv.localization.LOCATORS`:
        ``fused`` (the default, the best one) or ``paper`` (reproduces the paper).
        Each method's constants are in its own section.

    A section not given starts from the method's defaults (:data:`METHOD_PRESETS` over the
    section class's defaults), so ``Config()`` is the fused method as every command runs it
    and ``Config(method="paper")`` the paper's. ``pedenv.localization.configure`` switches
    a config to another method. A saved config without ``method`` (as written before the
    field existed) loads as ``fused``; the fields it names keep their values.
    """

    method: str = DEFAULT_METHOD
    # None (the default): the method's defaults, filled in by __post_init__
    tracking: TrackingConfig = None  # type: ignore[assignment]
    paper: PaperConfig = None  # type: ignore[assignment]
    kalman: KalmanConfig = None  # type: ignore[assignment]
    fused: FusedConfig = None  # type: ignore[assignment]
    redetect: RedetectConfig = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        if not isinstance(self.method, str) or not self.method:
            raise InputError(f"method must be the name of a position method, got {self.method!r}")
        preset = METHOD_PRESETS.get(self.method, {})
        for name, kind in SECTIONS.items():
            if getattr(self, name) is None:
                object.__setattr__(self, name, kind(**preset.get(name, {})))

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> Config:
        unknown = set(data) - set(SECTIONS) - {"method"}
        if unknown:
            raise InputError(f"unknown config section(s): {', '.join(sorted(unknown))}; "
                             f"valid: method, {', '.join(SECTIONS)}")
        method = data.get("method", DEFAULT_METHOD)
        preset = METHOD_PRESETS.get(method, {}) if isinstance(method, str) else {}
        built = {}
        for name, kind in SECTIONS.items():
            values = data.get(name, {})
            if not isinstance(values, dict):
                raise InputError(f"config.{name} must be an object of fields, got {type(values).__name__}")
            names = {f.name for f in dataclasses.fields(kind)}
            extra = set(values) - names
            if extra:
                raise InputError(
                    f"unknown field(s) in config.{name}: {', '.join(sorted(extra))}; valid: {', '.join(sorted(names))}"
                )
            built[name] = kind(**{**preset.get(name, {}), **values})
        return cls(method=method, **built)

    def replace(self, method: str | None = None, **sections) -> Config:
        """A copy with the method or some sections' fields changed:
        ``cfg.replace(paper={"refine": False})``. A new ``method`` here keeps every section
        as it is; :func:`pedenv.localization.configure` switches to a method with its defaults."""
        data = self.to_dict()
        if method is not None:
            data["method"] = method
        for name, values in sections.items():
            if name not in SECTIONS:
                raise InputError(f"unknown config section {name!r}; valid: {', '.join(SECTIONS)}")
            data[name] = {**data[name], **values}
        return Config.from_dict(data)

    def save(self, path: str | Path) -> None:
        Path(path).write_text(json.dumps(self.to_dict(), indent=2, allow_nan=False) + "\n")

    @classmethod
    def load(cls, path: str | Path) -> Config:
        """The config saved at ``path`` (JSON); every error names the file."""
        path = Path(path)
        text = read_text(path, "the config")
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise InputError(f"{path}: the config is not valid JSON (line {exc.lineno}, column {exc.colno}: "
                             f"{exc.msg})") from None
        if not isinstance(data, dict):
            raise InputError(f"{path}: a config must be a JSON object of sections, got {type(data).__name__}")
        try:
            return cls.from_dict(data)
        except InputError as exc:
            raise InputError(f"{path}: {exc}") from None


#: Section name -> its class.
SECTIONS: dict[str, type] = {"tracking": TrackingConfig, "paper": PaperConfig, "kalman": KalmanConfig,
                             "fused": FusedConfig, "redetect": RedetectConfig}
