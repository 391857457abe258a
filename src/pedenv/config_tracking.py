"""The tracker's settings (sections ``tracking`` and ``kalman`` of :class:`pedenv.config.Config`).

Every field is checked on construction by :mod:`pedenv.validation` (type, finiteness, a
documented range whose upper bound keeps each frame's memory and time bounded).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from pedenv.validation import check_fields, count, flag, number

#: Most frames a track may go undetected before it is dropped (``tracking.max_misses``).
MAX_MISSES = 300
#: The person score from which a detection may start a track (the two-band association,
#: ``tracking.low_score_threshold``): the pose backends' own threshold, so the first band is
#: what the paper's tracker sees. Read by :mod:`pedenv.tracking.recall`.
START_SCORE_THRESHOLD = 0.25


@dataclass(frozen=True)
class TrackingConfig:
    """Association of skeletons in the image (Sec. III-B).

    giou_threshold: a detection and a track overlap when their generalized IoU is above
        this (in [-1, 1)). The authors' public code uses -0.3. Raising it makes the
        tracker start new tracks more readily; lowering it lets distant boxes be joined.
    max_misses: a track is dropped after this many consecutive frames without a
        detection (the paper: 3). Raising it keeps tracks alive through occlusions: a
        missed track stays in the association in the image, where a person walking beside
        the one it lost cannot take its place unopposed (with ``memory_s`` a track past it is
        only remembered, and recalled by detections no live track took). At most
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
        in ByteTrack. Detections scoring below
        :data:`pedenv.tracking.recall.START_SCORE_THRESHOLD` (0.25) but at least this may only
        continue a track, never start one; detections below it are ignored. Both bands go
        into one assignment, the low band paying
        :data:`pedenv.tracking.tracker.LOW_SCORE_COST` extra, so a sure detection still wins
        a track over a weak one, but a weak detection of a half-hidden neighbour keeps a sure
        one from taking the neighbour's track (KITTI 0016 frame 7; ByteTrack's strictly
        sequential stages swap those two). Needs a pose backend that reports them
        (``OnnxPose(score_threshold=0.1)``). Lowering it keeps more occluded people's tracks
        alive, and lets more clutter continue a track. The ``fused`` preset uses 0.1.
    ground_gate: beyond the paper, off (0) by default: each track's Kalman-predicted ground
        position is projected into the image; a detection whose box foot point lies
        farther than this squared Mahalanobis distance (2 dof, pixels) from it cannot be
        associated with the track, and nearer ones pay the distance over the gate (times
        :data:`pedenv.tracking.recall.GROUND_COST_WEIGHT`) on top of the negative GIoU. Keeps
        two people side by side or crossing apart when their boxes overlap. The projected
        covariance is generous (it holds the road's height and a range bias,
        :mod:`pedenv.tracking.projection`), so the gate can be tight: the ``fused`` preset
        uses 4 (5.9 id switches per 100 matches on the first 6 s of the seed-0 terrain
        scenes, 7.3 with 16). Lowering it splits tracks more readily. The gate and the memory
        abstain in a frame whose projections contradict the image (a wrong calibration:
        :data:`pedenv.tracking.recall.CAMERA_CHECK`).
    memory_s: beyond the paper, off (0) by default: a track missed ``max_misses`` times is
        not dropped but remembered this many seconds with its Kalman state; a new
        detection no track took in the image whose foot point lies within
        :data:`pedenv.tracking.recall.MEMORY_GATE` (squared Mahalanobis distance, 2 dof) of a
        remembered (or just missed) track's predicted ground position gets that track's id
        back. Raising it bridges longer occlusions, with more chance of handing an old id to
        someone else. The ``fused`` preset uses 2 s. Needs the camera (the model passes it).

    Accepted values (:mod:`pedenv.validation`; the upper bounds lie far beyond any use and
    keep a frame's work bounded): giou_threshold [-1, 1); max_misses 1..300; max_height_ratio
    0 or (1, 100]; low_score_threshold 0 or (0, 0.25] (below the start score); ground_gate
    [0, 1000]; memory_s [0, 60]; the switches true or false.
    """

    giou_threshold: float = number(-0.3, -1.0, 1.0, high_open=True)
    max_misses: int = count(3, 1, MAX_MISSES)
    yaw_compensation: bool = flag(True)
    max_height_ratio: float = number(0.0, 1.0, 100.0, low_open=True, off=0.0)
    predict_motion: bool = flag(False)
    low_score_threshold: float = number(0.0, 0.0, START_SCORE_THRESHOLD, low_open=True, off=0.0)
    ground_gate: float = number(0.0, 0.0, 1000.0)
    memory_s: float = number(0.0, 0.0, 60.0)

    #: Fields earlier versions saved that are now module constants, with their fixed values (the
    #: constants named in the docstring); a saved config may hold them at these values only.
    RETIRED: ClassVar[dict[str, object]] = {
        "start_score_threshold": 0.25,
        "low_score_cost": 0.5,
        "ground_cost_weight": 1.0,
        "memory_gate": 9.21,
        "camera_check": 0.34}

    @property
    def pose_score_threshold(self) -> float | None:
        """The person score threshold a pose network should run at so the low band reaches
        the tracker: ``low_score_threshold`` while the two-band association is on, else
        None (the backend's own threshold; the paper's input stays as it was)."""
        return self.low_score_threshold if self.low_score_threshold > 0 else None

    def __post_init__(self) -> None:
        check_fields("tracking", self)


@dataclass(frozen=True)
class KalmanConfig:
    """Constant-velocity Kalman filter on the ground-plane position (Sec. III-C).

    The paper names the filter but not its noise; these defaults were tuned on the
    built-in scenes.

    enabled: filter the positions (off: raw per-frame estimates).
    acceleration_std_mps2: white-noise acceleration of a pedestrian (Q via filterpy's
        ``Q_discrete_white_noise``). Raising it follows turns faster, smooths less.
    The measurement noise R comes with each measurement from the position method.

    restart_gate: beyond the paper, off (0) by default: a measurement whose squared
        Mahalanobis distance from the track's prediction exceeds this restarts the
        track's filter at the measurement (the track has switched to another person).
        Lowering it restarts more readily; the ``fused`` preset uses 25.

    A new track's velocity starts with the spread :data:`pedenv.kalman.INITIAL_VELOCITY_STD_MPS`.

    Accepted values: acceleration_std_mps2 (0, 100];
    restart_gate [0, 10000] (0 = off); enabled true or false.
    """

    enabled: bool = flag(True)
    acceleration_std_mps2: float = number(1.0, 0.0, 100.0, low_open=True)
    restart_gate: float = number(0.0, 0.0, 10000.0)

    #: Fields earlier versions saved that are now module constants, with their fixed values (the
    #: constants named in the docstring); a saved config may hold them at these values only.
    RETIRED: ClassVar[dict[str, object]] = {
        "initial_velocity_std_mps": 2.0}

    def __post_init__(self) -> None:
        check_fields("kalman", self)
