"""The tracker's settings (sections ``tracking`` and ``kalman`` of :class:`pedenv.config.Config`).

Every field is checked on construction by :mod:`pedenv.validation` (type, finiteness, a
documented range whose upper bound keeps each frame's memory and time bounded).
"""

from __future__ import annotations

from dataclasses import dataclass

from pedenv.validation import check_fields, check_number, count, flag, number

#: Most frames a track may go undetected before it is dropped (``tracking.max_misses``).
MAX_MISSES = 300


@dataclass(frozen=True)
class TrackingConfig:
    """Association of skeletons in the image (Sec. III-B).

    giou_threshold: a detection and a track overlap when their generalized IoU is above
        this (in [-1, 1)). The authors' public code uses -0.3. Raising it makes the
        tracker start new tracks more readily; lowering it lets distant boxes be joined.
    max_misses: a track is dropped after this many consecutive frames without a
        detection (the paper: 3). Raising it keeps tracks alive through occlusions. At most
        :data:`MAX_MISSES` (300, 10 s at 30 Hz; ``memory_s`` bridges longer occlusions): every
        missed track stays in the association, so the cap bounds the tracks a run holds.
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

    Accepted values (:mod:`pedenv.validation`; the upper bounds lie far beyond any use and
    keep a frame's work bounded): giou_threshold [-1, 1); max_misses 1..300; max_height_ratio
    0 or (1, 100]; start_score_threshold [0, 1]; low_score_threshold 0 or (0,
    start_score_threshold]; low_score_cost [0, 2]; ground_gate and memory_gate up to 1000;
    ground_cost_weight [0, 10]; memory_s [0, 60]; camera_check [0, 1]; the switches true or false.
    """

    giou_threshold: float = number(-0.3, -1.0, 1.0, high_open=True)
    max_misses: int = count(3, 1, MAX_MISSES)
    yaw_compensation: bool = flag(True)
    max_height_ratio: float = number(0.0, 1.0, 100.0, low_open=True, off=0.0)
    predict_motion: bool = flag(False)
    low_score_threshold: float = 0.0
    start_score_threshold: float = number(0.25, 0.0, 1.0)
    low_score_cost: float = number(0.5, 0.0, 2.0)
    ground_gate: float = number(0.0, 0.0, 1000.0)
    ground_cost_weight: float = number(1.0, 0.0, 10.0)
    memory_s: float = number(0.0, 0.0, 60.0)
    memory_gate: float = number(9.21, 0.0, 1000.0, low_open=True)
    camera_check: float = number(0.34, 0.0, 1.0)

    @property
    def pose_score_threshold(self) -> float | None:
        """The person score threshold a pose network should run at so the low band reaches
        the tracker: ``low_score_threshold`` while the two-band association is on, else
        None (the backend's own threshold; the paper's input stays as it was)."""
        return self.low_score_threshold if self.low_score_threshold > 0 else None

    def __post_init__(self) -> None:
        check_fields("tracking", self)
        check_number("tracking.low_score_threshold", self.low_score_threshold, 0.0, self.start_score_threshold,
                     low_open=True, off=0.0)


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

    Accepted values: acceleration_std_mps2 and initial_velocity_std_mps (0, 100];
    restart_gate [0, 10000] (0 = off); enabled true or false.
    """

    enabled: bool = flag(True)
    acceleration_std_mps2: float = number(1.0, 0.0, 100.0, low_open=True)
    initial_velocity_std_mps: float = number(2.0, 0.0, 100.0, low_open=True)
    restart_gate: float = number(0.0, 0.0, 10000.0)

    def __post_init__(self) -> None:
        check_fields("kalman", self)
