"""The position methods' settings (sections ``paper`` and ``fused`` of :class:`pedenv.config.Config`).

Every field is checked on construction by :mod:`pedenv.validation` (type, finiteness, a
documented range whose upper bound keeps each frame's memory and time bounded).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from pedenv.validation import check_choice, check_fields, check_sequence, choice, count, flag, number, sequence

#: Most refinement iterations per frame (``paper.refinement_steps``).
MAX_REFINEMENT_STEPS = 200
#: Most past observations per track (``fused.history_length``).
MAX_HISTORY_LENGTH = 100

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
    refinement_steps: number of refinement iterations (the paper: 15; at most
        :data:`MAX_REFINEMENT_STEPS`, 200). Each frame runs them over a (steps, N) array, so
        the cap bounds a frame's refinement at about 13 times the paper's cost; from step 95
        on (``lambda >= 100``) a step closes under 1 % of the remaining height mismatch.
    refinement_lambda_offset: ``c`` in ``lambda = r + c`` for step ``r`` = 1..steps (the
        paper: 5). Each step scales the distance by ``1 + (h_est / h_orig - 1) / lambda``;
        raising ``c`` makes the refinement move less from the initial estimate.
    max_distance_m: triangulated keypoints farther than this from the camera are
        discarded as degenerate, and no position is reported farther than this
        (horizontally) from the camera: the model clamps it as ``fused.max_range_m``.

    The measurement noise and the parallel-ray guard are constants of
    :mod:`pedenv.localization.paper` (the paper gives neither).

    Accepted values (:mod:`pedenv.validation`): low_confidence_fraction [0, 1);
    person_height_m [0.3, 2.5]; refinement_steps 0..200; refinement_lambda_offset (0, 1000];
    max_distance_m [1, 10000]; refine true or false.
    """

    low_confidence_fraction: float = number(0.3, 0.0, 1.0, high_open=True)
    initial_estimate: str = choice("all-keypoints", INITIAL_ESTIMATES)
    refine: bool = flag(True)
    person_height_m: float = number(1.7, 0.3, 2.5)
    refinement_steps: int = count(15, 0, MAX_REFINEMENT_STEPS)
    refinement_lambda_offset: float = number(5.0, 0.0, 1000.0, low_open=True)
    max_distance_m: float = number(500.0, 1.0, 10000.0)

    #: Fields earlier versions saved that are now module constants, with their fixed values (the
    #: constants named in the docstring); a saved config may hold them at these values only.
    RETIRED: ClassVar[dict[str, object]] = {
        "min_parallax_rad": 1e-06,
        "measurement_std_m": 0.5,
        "measurement_std_rel": 0.1}

    def __post_init__(self) -> None:
        check_fields("paper", self)


FUSED_CUES = ("ground", "triangulation", "height")

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
    ground_max_distance_m: the ground cue declines beyond this horizontal distance (a
        vehicle-mounted camera: its pitch and height over the road change as it drives).
        A ``static`` camera (``Camera.mount``) has no such limit, see below.
    static_ground_height_std_m: the ground's unevenness under a pedestrian against a static
        camera's calibrated plane (paving, gutters), metres, per person; a static camera does
        not pitch or bounce, so this and its calibration's own error (the next two) replace
        the road's height and curvature spread (``ROAD_HEIGHT_STD_M`` and
        ``ROAD_CURVATURE_STD_PER_M`` of :mod:`pedenv.localization.fused.ground`). Raising it
        widens its ground cue along the ray.
    static_camera_tilt_std_deg: how far a static camera's calibrated pitch and roll (each)
        may be off, degrees, per camera. An estimated calibration tilts the ground it cuts by
        ``d`` times its error at ``d`` metres, so the foot point's range errs by about
        ``r^2 / h`` times it (range ``r``, camera height ``h``): 0.2 deg moves a person 25 m
        from a camera 1.73 m up by 1.3 m. 0.2: a hand fit of a ground grid, as UCMCTrack's
        MOT17 cameras were made (its tool sets the angles in 0.1 deg steps and draws dots
        0.5 m apart out to 10 m, whose farthest rows lie 0.5 deg apart from 1.73 m: a misfit
        under half a row is hard to see). A judgment of that method, not fitted to any
        truth. 0 for an exactly known camera (the synthetic scenes). Raising it makes the
        ground cue count less far from the camera, where the height cue takes over.
    static_camera_height_std_m: how far a static camera's calibrated height above the ground
        may be off, metres (every ground range scales with it). 0.04: one step of that tool's
        height control. 0 for an exactly known camera. Raising it widens the ground cue along the ray.
    ankle_keypoint_offset_m: how far the pose source's ankle keypoint sits above the
        anatomical ankle (0.046 of ``person_height_mean_m``, 0.079 m above the ground),
        metres: the ground cue cuts the ankle's ray with the ground raised by both. 0.039:
        the real YOLO11n-pose network's lower ankle lies 0.118 m above the 3D boxes' bottom
        on KITTI (median of 8 persons, IQR 0.107-0.139;
        ``benchmarks/person_offsets.py --ankle-heights``). The synthetic skeletons put it at
        the anatomical height (0 for them). Raising it moves ground-cue estimates nearer,
        by about ``r * offset / h``.
    ankle_keypoint_offset_std_m: how far one person's ankle keypoint may sit off
        ``ankle_keypoint_offset_m``, metres, per person (shoes, gait, where the network puts the
        joint on each body and camera). A static camera's ground cue carries it like a height
        error of the ground (it repeats for the person): at range ``r`` from a camera ``h`` up it
        moves the foot point by about ``r`` times it over ``h`` (0.26 m at 7 m from 1.13 m up).
        0.042: the spread (1.4826 MAD) across the 14 KITTI and nuScenes persons of the real
        network's lower-ankle height above the 3D boxes' bottom
        (``benchmarks/person_offsets.py --ankle-heights``; KITTI alone 0.026, its median 0.118 m
        against nuScenes' 0.165 m). On a vehicle the road's height under the person
        (``ROAD_HEIGHT_STD_M``, 0.08) is the larger term and holds it. 0 for skeletons whose
        ankles sit at the anatomical height (the synthetic scenes). Raising it widens a static
        camera's ground cue along the ray, most for a low camera.
    history_length: past observations of a track kept for triangulation. Raising it
        gives more baseline when driving slowly, at more cost per pedestrian; older rays
        add little (a walker's drift grows with their age): on the built-in terrain
        scenes 6 gave the exact-skeleton error of 10 and a lower detector-model one
        (7.3 vs 7.7 %), at 6/10 of the triangulation's cost. At most
        :data:`MAX_HISTORY_LENGTH` (100, over 3 s at 30 Hz): each track holds this many
        rows, so the cap bounds the memory per track.
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

    The cues' model constants (the ankle's lift, the road's height and curvature, a static
    camera's range limit, the stance, the body's sideways spread, triangulation's baseline,
    parallax, walker drift and outlier gate, the fusion's gate) are named constants of
    :mod:`pedenv.localization.fused` beside the code that uses them, each with its source.

    Each cue splits its covariance into the part new every frame (pixel noise, gait) and
    the part that repeats for the same person (height prior, road under them, a walker's
    drift); the model filters the first and adds the second to what it reports.

    Accepted values (:mod:`pedenv.validation`; metres, pixels and ratios far beyond any real
    camera or person): 1 to 3 cues; person_height_mean_m [0.5, 2.5]; person_height_std_m
    (0, 0.5]; keypoint_pixel_std (0, 100]; min_keypoint_confidence [0, 1);
    ground_max_distance_m [1, 1000]; static_ground_height_std_m [0, 1];
    static_camera_tilt_std_deg [0, 10]; static_camera_height_std_m [0, 5];
    ankle_keypoint_offset_m [-0.5, 0.5]; ankle_keypoint_offset_std_m [0, 0.5]; history_length
    1..100; keypoint_span_scale [0.5, 1.5]; keypoint_span_std [0, 0.5]; max_range_m [5, 10000].
    """

    cues: tuple[str, ...] = sequence(FUSED_CUES, len(FUSED_CUES), choices=FUSED_CUES)
    person_height_mean_m: float = number(1.72, 0.5, 2.5)
    person_height_std_m: float = number(0.09, 0.0, 0.5, low_open=True)
    keypoint_pixel_std: float = number(3.0, 0.0, 100.0, low_open=True)
    min_keypoint_confidence: float = number(0.3, 0.0, 1.0, high_open=True)
    ground_max_distance_m: float = number(20.0, 1.0, 1000.0)
    static_ground_height_std_m: float = number(0.02, 0.0, 1.0)
    static_camera_tilt_std_deg: float = number(0.2, 0.0, 10.0)
    static_camera_height_std_m: float = number(0.04, 0.0, 5.0)
    ankle_keypoint_offset_m: float = number(0.039, -0.5, 0.5)
    ankle_keypoint_offset_std_m: float = number(0.042, 0.0, 0.5)
    history_length: int = count(6, 1, MAX_HISTORY_LENGTH)
    keypoint_span_scale: float = number(1.0, 0.5, 1.5)
    keypoint_span_std: float = number(0.017, 0.0, 0.5)
    max_range_m: float = number(200.0, 5.0, 10000.0)

    #: Fields earlier versions saved that are now module constants, with their fixed values (the
    #: constants named in the docstring); a saved config may hold them at these values only.
    RETIRED: ClassVar[dict[str, object]] = {
        "ankle_height_std_m": 0.04,
        "road_height_std_m": 0.08,
        "road_curvature_std_per_m": 0.001,
        "static_ground_max_relative_std": 0.2,
        "stance_std_m": 0.14,
        "lateral_std_m": 0.05,
        "min_baseline_m": 0.3,
        "min_parallax_rad": 0.01,
        "pedestrian_speed_std_mps": 0.8,
        "outlier_sigma": 3.0,
        "gate_probability": 0.999}

    def __post_init__(self) -> None:
        cues = [c for c in self.cues.split(",") if c] if isinstance(self.cues, str) else self.cues
        cues = check_sequence("fused.cues", cues, len(FUSED_CUES))
        for cue in cues:
            check_choice("fused.cues entry", cue, FUSED_CUES)
        object.__setattr__(self, "cues", cues)
        check_fields("fused", self)
