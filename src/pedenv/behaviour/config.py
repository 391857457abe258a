"""``Config.behaviour``: every threshold of the behaviour cues, named, documented and validated.

Beyond the paper: off by default (``--method paper`` has no behaviour cues); the ``fused``
preset turns it on. Errors name ``behaviour.<field>``.
"""

from __future__ import annotations

from dataclasses import dataclass

from pedenv.errors import InputError
from pedenv.validation import check_below, check_fields, check_number, check_sequence, count, flag, number, shown

#: Horizons (s) of the predicted path.
DEFAULT_HORIZONS_S = (0.5, 1.0, 2.0, 3.0)


@dataclass(frozen=True)
class BehaviourConfig:
    """What the pedestrian is about to do (:mod:`pedenv.behaviour`).

    enabled: compute the cues (orientation, facing, motion state, predicted path, conflict).
    orientation_bins: cells of the grid filter on the circle (12..360; 72 = 5 degrees).
        More cells resolve the heading finer and cost more.
    orientation_interval_s: the heading grids (skeleton cue, walking direction, filter, the
        reported yaw, its spread and availability, body and head facing) are updated when this
        long has passed since their last update, all tracks together; in between, each track
        reports those of its last update (a track new since then: ``unavailable``) and the next
        update predicts its grid over the whole gap. 0 updates them every frame; raising it
        costs less per frame and reacts later (by at most this long). The default, 0.3 s (every
        third frame at 10 Hz), keeps the cues' cost down (``benchmarks/behaviour_cost.py``).
    person_height_m: the body height the expected shoulder and hip widths are scaled from.
    keypoint_pixel_std: pixel noise of one keypoint; turns the shoulder and hip widths' pixel
        noise into the spread of their width ratios.
    min_keypoint_confidence: keypoints below this confidence are not used by the skeleton cue.
    width_ratio_std: spread of the apparent shoulder (hip) width as a share of the width
        expected at the person's range, beyond pixel noise (body shape, arms, a twisted
        torso). Raising it trusts the skeleton less against the walking direction.
    face_offset_std: spread of the nose's sideways offset from the ears (or shoulders) as a
        share of the offset in full profile. Raising it trusts the face less.
    left_right_swap_probability: how often the pose network swaps the person's left and right
        (a mixture weight of the mirrored angle). Raising it lets front and back stay open longer.
    walking_direction_std_deg: how far the body may face away from the walking direction.
    min_walking_speed_mps: the walking direction is a cue only above this filtered speed ...
    speed_sigmas: ... and when the speed exceeds this many of its standard deviations.
    heading_random_walk_deg: how fast an unobserved heading spreads, degrees per square root
        of a second (a gap of seconds leaves it unavailable).
    available_std_deg: the orientation is ``available`` when the posterior's spread about its
        mode is below this, ``sign_unknown`` when only its axis (mode or mode + 180 deg) is.
    facing_half_angle_deg: the body (head) faces the ego when it is turned within this angle of
        the direction to the camera.
    walk_enter_mps, walk_exit_mps: a standing pedestrian becomes walking when the filtered speed
        exceeds ``walk_enter_mps`` by ``speed_sigmas`` standard deviations, and a walking one
        stands again below ``walk_exit_mps`` (hysteresis: exit < enter).
    run_enter_mps, run_exit_mps: the same for running.
    horizons_s: the predicted path's times ahead, seconds, increasing (at most 8, each <= 10 s).
    ego_window_s: the ego's speed and yaw rate are fitted over its poses this far back.
    max_ego_gap_s: a gap between two frames longer than this forgets the ego's motion.
    max_yaw_rate_radps: a fitted ego yaw rate is clipped to this (a spike is not followed).
    max_ego_acceleration_mps2: the ego's fitted acceleration (or braking) is clipped to this;
        0 predicts at constant speed.
    ego_trend_s: for this long into the prediction the ego's acceleration changes at its fitted
        jerk (a start or a stop still building up), then holds; 0 predicts at the acceleration now.
    max_ego_jerk_mps3: the fitted jerk is clipped to this (a noisy pose is not followed far).
    ego_speed_std_mps, ego_yaw_rate_std_radps: the spread of the ego's speed and yaw rate over
        the horizon (the driver may brake or steer); with no motion known, 5 times as much.
    corridor_half_width_m: half the width of the corridor around the ego's path (half the
        vehicle's width plus a margin).
    corridor_front_m: the corridor reaches this far beyond the path's end (the vehicle's front).
    conflict_horizon_s: how far ahead the ego's path and the corridor entry are predicted.
    conflict_step_s: time step of that prediction.
    max_pedestrian_speed_mps: the corridor's prediction takes a filtered velocity faster than this
        at this speed, in its direction (a track whose range jumps can show 5-10 m/s; people
        rarely run faster). Raising it follows such tracks; the reported path is not changed.
    conflict_probability: a pedestrian whose probability of entering the corridor within the
        horizon is at least this is flagged ``conflict``.
    """

    enabled: bool = flag(False)
    orientation_bins: int = count(72, 12, 360)
    orientation_interval_s: float = number(0.3, 0.0, 1.0)
    person_height_m: float = number(1.72, 0.5, 2.5)
    keypoint_pixel_std: float = number(3.0, 0.01, 100.0)
    min_keypoint_confidence: float = number(0.3, 0.0, 0.99)
    width_ratio_std: float = number(0.25, 0.01, 2.0)
    face_offset_std: float = number(0.5, 0.01, 5.0)
    left_right_swap_probability: float = number(0.1, 0.0, 0.5)
    walking_direction_std_deg: float = number(20.0, 1.0, 90.0)
    min_walking_speed_mps: float = number(0.5, 0.0, 5.0)
    speed_sigmas: float = number(1.5, 0.0, 10.0)
    heading_random_walk_deg: float = number(45.0, 0.0, 360.0)
    available_std_deg: float = number(40.0, 1.0, 90.0)
    facing_half_angle_deg: float = number(60.0, 1.0, 90.0)
    walk_enter_mps: float = number(0.6, 0.0, 5.0)
    walk_exit_mps: float = number(0.35, 0.0, 5.0)
    run_enter_mps: float = number(2.8, 0.0, 15.0)
    run_exit_mps: float = number(2.3, 0.0, 15.0)
    horizons_s: tuple[float, ...] = DEFAULT_HORIZONS_S
    ego_window_s: float = number(0.5, 0.05, 5.0)
    max_ego_gap_s: float = number(1.0, 0.05, 30.0)
    max_yaw_rate_radps: float = number(1.0, 0.01, 5.0)
    max_ego_acceleration_mps2: float = number(4.0, 0.0, 15.0)
    ego_trend_s: float = number(1.0, 0.0, 5.0)
    max_ego_jerk_mps3: float = number(2.0, 0.0, 50.0)
    ego_speed_std_mps: float = number(0.5, 0.0, 10.0)
    ego_yaw_rate_std_radps: float = number(0.05, 0.0, 2.0)
    corridor_half_width_m: float = number(1.5, 0.1, 10.0)
    corridor_front_m: float = number(2.5, 0.0, 20.0)
    conflict_horizon_s: float = number(2.0, 0.1, 10.0)
    conflict_step_s: float = number(0.1, 0.01, 1.0)
    max_pedestrian_speed_mps: float = number(4.0, 0.5, 15.0)
    conflict_probability: float = number(0.3, 0.01, 0.99)

    def __post_init__(self) -> None:
        check_fields("behaviour", self)
        if not self.walk_exit_mps < self.walk_enter_mps <= self.run_exit_mps < self.run_enter_mps:
            raise InputError("behaviour: walk_exit_mps < walk_enter_mps <= run_exit_mps < run_enter_mps must hold, got "
                             f"{self.walk_exit_mps}, {self.walk_enter_mps}, {self.run_exit_mps}, {self.run_enter_mps}")
        h = check_sequence("behaviour.horizons_s", self.horizons_s, 8)
        object.__setattr__(self, "horizons_s", h)
        for value in h:
            check_number("behaviour.horizons_s", value, 0.0, 10.0, low_open=True)
        if any(b <= a for a, b in zip(h, h[1:])):
            raise InputError(f"behaviour.horizons_s must be increasing times, got {shown(h)}")
        check_below("behaviour.conflict_step_s", self.conflict_step_s,
                    "behaviour.conflict_horizon_s", self.conflict_horizon_s, equal_ok=True)
