"""The ego's path from its recent poses: standing, reversing, turning, a yaw-rate spike, a gap."""

import numpy as np
import pytest

from pedenv.behaviour import ego_path
from pedenv.behaviour.ego_path import EgoHistory, predict_ego_path
from pedenv.records import EgoPose
from pedenv.synthetic.ego_motion import integrate_track, smooth_step

TIMES = np.linspace(0.0, 2.0, 21)


def _history(poses, dt=0.1):
    h = EgoHistory()
    for k, (x, y, yaw) in enumerate(poses):
        h.add(k * dt, EgoPose.from_xy_yaw(x, y, yaw))
    return h


@pytest.mark.parametrize("name, poses, speed, rate", [
    ("driving", [(k, 0.0, 0.0) for k in range(6)], 10.0, 0.0),
    ("standing", [(3.0, 1.0, 0.4)] * 6, 0.0, 0.0),
    ("reversing", [(-0.2 * k, 0.0, 0.0) for k in range(6)], -2.0, 0.0),
    ("turning", [(np.sin(0.03 * k) / 0.03, (1 - np.cos(0.03 * k)) / 0.03, 0.03 * k) for k in range(6)], 10.0, 0.3),
])
def test_speed_and_yaw_rate(name, poses, speed, rate):
    m = _history(poses).motion()
    assert m.known and m.speed == pytest.approx(speed, abs=0.02) and m.yaw_rate == pytest.approx(rate, abs=0.01)


def test_a_turning_ego_path_follows_the_arc():
    h = _history([(np.sin(0.03 * k) / 0.03, (1 - np.cos(0.03 * k)) / 0.03, 0.03 * k) for k in range(6)])
    pose = EgoPose.from_xy_yaw(np.sin(0.15) / 0.03, (1 - np.cos(0.15)) / 0.03, 0.15)
    path = predict_ego_path(pose, h.motion(), TIMES)
    end = 0.15 + 0.3 * 2.0
    assert np.allclose(path.xy[-1], [np.sin(end) / 0.03, (1 - np.cos(end)) / 0.03], atol=0.05)
    assert path.lateral_std[0] == 0 and path.lateral_std[-1] > path.lateral_std[10] > 0


def test_a_yaw_rate_spike_is_clipped_and_widens_the_spread():
    m = _history([(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (2.0, 0.0, 1.2)]).motion()
    assert m.yaw_rate == ego_path.MAX_YAW_RATE_RADPS and m.yaw_rate_std > ego_path.EGO_YAW_RATE_STD_RADPS + 1.0


def test_a_gap_of_seconds_forgets_the_motion():
    h = _history([(k, 0.0, 0.0) for k in range(6)])
    h.add(10.0, EgoPose.from_xy_yaw(30.0, 0.0, 0.0))
    m = h.motion()
    assert not m.known and m.speed == 0 and m.speed_std == 5 * ego_path.EGO_SPEED_STD_MPS
    path = predict_ego_path(EgoPose.from_xy_yaw(30.0, 0.0, 0.0), m, TIMES)
    assert np.isfinite(path.xy).all() and np.allclose(path.xy, [30.0, 0.0])


def test_an_accelerating_ego_reaches_farther_and_a_braking_one_stops():
    start = _history([(0.5 * 2.0 * (0.1 * k) ** 2, 0.0, 0.0) for k in range(6)])  # 2 m/s^2 from rest
    m = start.motion()
    assert m.acceleration == pytest.approx(2.0, abs=0.05) and m.speed == pytest.approx(1.0, abs=0.05)
    path = predict_ego_path(EgoPose.from_xy_yaw(0.25, 0.0, 0.0), m, TIMES)
    assert path.length == pytest.approx(1.0 * 2 + 0.5 * 2.0 * 4, abs=0.1)
    brake = _history([(10 * 0.1 * k - 0.5 * 5.0 * (0.1 * k) ** 2, 0.0, 0.0) for k in range(6)])  # 10 m/s, -5 m/s^2
    m = brake.motion()
    path = predict_ego_path(EgoPose.from_xy_yaw(0.0, 0.0, 0.0), m, TIMES)
    assert m.acceleration == pytest.approx(-4.0)  # clipped to MAX_EGO_ACCELERATION_MPS2
    assert path.length == pytest.approx(m.speed**2 / 8.0, abs=0.05) and path.direction == 1.0


def _scripted(speed, yaw_rate, now):
    """The ego of a scenario profile (:func:`pedenv.synthetic.ego_motion.integrate_track`): its
    motion fitted from the poses up to ``now`` (s, 10 Hz), its predicted path and its true path
    (21 samples, 0 .. 2 s ahead)."""
    track = integrate_track(np.round(np.arange(0.0, now + 2.0 + 1e-9, 0.1), 6), speed, yaw_rate)
    h, k = EgoHistory(), int(round(now / 0.1))
    for i in range(k + 1):
        h.add(track.times[i], EgoPose.from_xy_yaw(*track.xy[i], track.yaw[i]))
    m = h.motion()
    path = predict_ego_path(EgoPose.from_xy_yaw(*track.xy[k], track.yaw[k]), m, TIMES, ego_path.EGO_TREND_S,
                            ego_path.MAX_EGO_ACCELERATION_MPS2)
    return m, path, track.xy[k:k + 21]


def test_an_ego_starting_from_standstill_is_followed_through_its_jerk():
    # start-from-standstill's profile, 0.5 s into the start: 2.69 m covered in the next 2 s; the
    # acceleration alone (0.55 m/s^2, as EGO_TREND_S = 0) reaches 1.38 m, the fit of main before 0.83 m
    m, path, truth = _scripted(lambda t: 11.0 * smooth_step(t, 4.0, 7.0), lambda t: 0.0 * t, 4.5)
    assert m.speed == pytest.approx(0.138, abs=0.005) and m.acceleration == pytest.approx(0.551, abs=0.01)
    assert m.jerk == pytest.approx(1.10, abs=0.02)
    assert path.length == pytest.approx(2.66, abs=0.03) and np.linalg.norm(path.xy[-1] - truth[-1]) < 0.05
    steady = predict_ego_path(EgoPose.from_xy_yaw(0.0, 0.0, 0.0), m, TIMES)  # no trend
    assert steady.length == pytest.approx(1.38, abs=0.03)


@pytest.mark.parametrize("now, rate, end_error", [(6.3, 0.235, 1.06), (6.4, 0.353, 0.04), (6.7, 0.327, 0.23)])
def test_an_ego_starting_a_turn_is_followed_by_its_yaw_rate_now(now, rate, end_error):
    # turn-intersection's onset (0.35 rad/s reached in 0.5 s from 6 s) at 5 m/s: the yaw rate
    # fitted now; the 0.5 s mean of main before gave 0.05, 0.11, 0.30 rad/s (2.9, 2.4, 0.5 m at 2 s)
    m, path, truth = _scripted(lambda t: 5.0 + 0.0 * t, lambda t: 0.35 * smooth_step(t, 6.0, 0.5), now)
    assert m.yaw_rate == pytest.approx(rate, abs=0.005)
    assert np.linalg.norm(path.xy[-1] - truth[-1]) == pytest.approx(end_error, abs=0.03)


def test_a_time_that_does_not_increase_starts_the_history_again():
    h = _history([(k, 0.0, 0.0) for k in range(6)])
    h.add(0.5, EgoPose.from_xy_yaw(5.0, 0.0, 0.0))  # the same time as the last pose
    m = h.motion()
    assert not m.known and m.speed == 0.0 and len(h.poses) == 1 and h.pairs == []


def _lengths(positions, yaw=0.0):
    """The predicted path's length at 2 s from each pose on (x, y) ``positions`` (10 Hz), from the 21st on."""
    h, out = EgoHistory(), []
    for k, (x, y) in enumerate(positions):
        h.add(0.1 * k, EgoPose.from_xy_yaw(x, y, yaw))
        if k >= 20:
            out.append(predict_ego_path(EgoPose.from_xy_yaw(x, y, yaw), h.motion(), TIMES, ego_path.EGO_TREND_S,
                                        ego_path.MAX_EGO_ACCELERATION_MPS2).length)
    return np.array(out)


def test_jittering_poses_give_a_steady_path():
    # 8 m/s with 5 mm of white jitter (ORB-SLAM3 on the KITTI drives: 2-10 mm): the quadratic's
    # acceleration and jerk put the end 3.9 m off (rms, 6.8 m at most); the line over 1 s does not
    x = 0.8 * np.arange(60) + np.random.default_rng(3).normal(0.0, 0.005, 60)
    lengths = _lengths(np.c_[x, np.zeros(60)])
    assert np.abs(lengths - 16.0).max() < 0.6 and np.sqrt(np.mean((lengths - 16.0) ** 2)) < 0.3


def test_a_parked_ego_whose_poses_drift_stands():
    # 4 mm of smooth drift (ORB-SLAM3 on the parked KITTI drives): read as a start, it made a 0.4 m path
    drift = 3.0 + 0.004 * np.sin(2 * np.pi * 0.1 * np.arange(60) / 1.5)
    assert _lengths(np.c_[drift, np.ones(60)], 0.4).max() == 0.0
