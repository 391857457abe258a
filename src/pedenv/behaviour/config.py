"""``Config.behaviour``: the behaviour cues' settings a user turns, named, documented and validated.

Beyond the paper: off by default (``--method paper`` has no behaviour cues); the ``fused``
preset turns it on. Errors name ``behaviour.<field>``. The cues' model constants (keypoint
noise, the skeleton cue's spreads, the walking direction, the heading's random walk, the ego's
fit and its limits, the corridor's time step and speed cap) are named constants of the module
that uses each (:mod:`pedenv.behaviour.orientation`, :mod:`pedenv.behaviour.motion_state`,
:mod:`pedenv.behaviour.estimator`, :mod:`pedenv.behaviour.ego_path`), each with its source.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from pedenv.errors import InputError
from pedenv.validation import (
    check_below,
    check_fields,
    check_number,
    check_sequence,
    count,
    flag,
    number,
    sequence,
    shown,
)

#: Horizons (s) of the predicted path.
DEFAULT_HORIZONS_S = (0.5, 1.0, 2.0, 3.0)


@dataclass(frozen=True)
class BehaviourConfig:
    """What the pedestrian is about to do (:mod:`pedenv.behaviour`).

    enabled: compute the cues (orientation, facing, motion state, predicted path, conflict).
    orientation_bins: cells of the grid filter on the circle (12..360; 72 = 5 degrees).
        Raising it resolves the heading finer and costs more per track.
    orientation_interval_s: the heading grids (skeleton cue, walking direction, filter, the
        reported yaw, its spread and availability, body and head facing) are updated when this
        long has passed since their last update, all tracks together; in between, each track
        reports those of its last update (a track new since then: ``unavailable``) and the next
        update predicts its grid over the whole gap. 0 updates them every frame; raising it
        costs less per frame and reacts later (by at most this long). The default, 0.3 s (every
        third frame at 10 Hz), keeps the cues' cost down (``benchmarks/behaviour_cost.py``).
    available_std_deg: the orientation is ``available`` when the posterior's spread about its
        mode is below this, ``sign_unknown`` when only its axis (mode or mode + 180 deg) is.
        Raising it reports an orientation sooner, with more spread.
    facing_half_angle_deg: the body (head) faces the ego when it is turned within this angle of
        the direction to the camera. Raising it counts more people as facing.
    walk_enter_mps, walk_exit_mps: a standing pedestrian becomes walking when the median of its
        true speed's posterior (the filtered velocity under a population prior on the speed,
        :func:`pedenv.behaviour.motion_state.speed_posterior`) exceeds ``walk_enter_mps``, and a
        walking one stands again below ``walk_exit_mps`` (hysteresis). Raising them calls fewer
        people walking. The defaults, 0.45 and 0.3 m/s, put the exit at the labelled standing
        bound of the KITTI drives' evaluation (0.3 m/s, docs/kitti_tracking.md).
    run_enter_mps, run_exit_mps: the same for running.
    horizons_s: the predicted path's times ahead, seconds, increasing (at most 8, each <= 10 s).
        More or farther horizons report more of the path, with wider spreads.
    corridor_half_width_m: half the width of the corridor around the ego's path (half the
        vehicle's width plus a margin). Raising it flags people farther to the side.
    corridor_front_m: the corridor reaches this far beyond the path's end (the vehicle's front).
    conflict_horizon_s: how far ahead the ego's path and the corridor entry are predicted.
        Raising it flags conflicts earlier, with wider spreads.

    The probability of entering the corridor is reported, not thresholded: the benchmarks flag
    a conflict from :data:`pedenv.behaviour.conflict.CONFLICT_PROBABILITY` (0.3).

    Accepted values, checked together where they bound one another: orientation_bins 12..360;
    orientation_interval_s [0, 1]; available_std_deg and facing_half_angle_deg [1, 90];
    walk_exit_mps < walk_enter_mps <= run_exit_mps < run_enter_mps, walk thresholds in [0, 5],
    run thresholds in [0, 15]; horizons_s 1 to 8 increasing times in (0, 10];
    corridor_half_width_m [0.1, 10]; corridor_front_m [0, 20]; conflict_horizon_s [0.1, 10],
    at least :data:`pedenv.behaviour.estimator.CONFLICT_STEP_S` (0.1 s).
    """

    enabled: bool = flag(False)
    orientation_bins: int = count(72, 12, 360)
    orientation_interval_s: float = number(0.3, 0.0, 1.0)
    available_std_deg: float = number(40.0, 1.0, 90.0)
    facing_half_angle_deg: float = number(60.0, 1.0, 90.0)
    walk_enter_mps: float = number(0.45, 0.0, 5.0)
    walk_exit_mps: float = number(0.3, 0.0, 5.0)
    run_enter_mps: float = number(2.8, 0.0, 15.0)
    run_exit_mps: float = number(2.3, 0.0, 15.0)
    horizons_s: tuple[float, ...] = sequence(DEFAULT_HORIZONS_S, 8, low=0.0, high=10.0, low_open=True, increasing=True)
    corridor_half_width_m: float = number(1.5, 0.1, 10.0)
    corridor_front_m: float = number(2.5, 0.0, 20.0)
    conflict_horizon_s: float = number(2.0, 0.1, 10.0)

    #: Fields earlier versions saved that are now module constants, with their fixed values (the
    #: constants named in the docstring); a saved config may hold them at these values only.
    RETIRED: ClassVar[dict[str, object]] = {
        "person_height_m": 1.72,
        "keypoint_pixel_std": 3.0,
        "min_keypoint_confidence": 0.3,
        "width_ratio_std": 0.25,
        "face_offset_std": 0.5,
        "left_right_swap_probability": 0.1,
        "walking_direction_std_deg": 20.0,
        "min_walking_speed_mps": 0.5,
        "speed_sigmas": 1.5,
        "heading_random_walk_deg": 45.0,
        "conflict_step_s": 0.1,
        "max_pedestrian_speed_mps": 4.0,
        "ego_window_s": 0.5,
        "max_ego_gap_s": 1.0,
        "max_yaw_rate_radps": 1.0,
        "max_ego_acceleration_mps2": 4.0,
        "ego_trend_s": 1.0,
        "max_ego_jerk_mps3": 2.0,
        "ego_speed_std_mps": 0.5,
        "ego_yaw_rate_std_radps": 0.05,
        "conflict_probability": 0.3}

    def __post_init__(self) -> None:
        check_fields("behaviour", self)
        check_below("behaviour.walk_exit_mps", self.walk_exit_mps, "behaviour.walk_enter_mps", self.walk_enter_mps)
        check_below("behaviour.walk_enter_mps", self.walk_enter_mps, "behaviour.run_exit_mps", self.run_exit_mps,
                    equal_ok=True)
        check_below("behaviour.run_exit_mps", self.run_exit_mps, "behaviour.run_enter_mps", self.run_enter_mps)
        h = check_sequence("behaviour.horizons_s", self.horizons_s, 8)
        object.__setattr__(self, "horizons_s", h)
        for value in h:
            check_number("behaviour.horizons_s", value, 0.0, 10.0, low_open=True)
        if any(b <= a for a, b in zip(h, h[1:])):
            raise InputError(f"behaviour.horizons_s must be increasing times, got {shown(h)}")
