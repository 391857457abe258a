"""Conflict with the corridor around the ego's path, on constructed pedestrians."""

import numpy as np
import pytest

from pedenv.behaviour.conflict import (
    CONFLICT_PROBABILITY,
    CORRIDOR_ACCELERATION_STD_MPS2,
    corridor_conflict,
    path_coordinates,
)
from pedenv.behaviour.ego_path import EgoMotion, predict_ego_path
from pedenv.behaviour.prediction import predict_path
from pedenv.records import EgoPose

TIMES = np.linspace(0.0, 2.0, 21)


def _conflict(motion, states, std=0.3, acceleration_std=0.5):
    path = predict_ego_path(EgoPose.from_xy_yaw(0.0, 0.0, 0.0), motion, TIMES)
    x = np.asarray(states, float)
    P = np.repeat(np.diag([std**2, 0.05, std**2, 0.05])[None], len(x), axis=0)
    pos, cov = predict_path(x, P, TIMES, acceleration_std)
    return corridor_conflict(path, pos, cov, 1.5, 2.5)


def test_a_pedestrian_crossing_in_front_of_a_driving_ego():
    # ego at 8 m/s; a pedestrian 12 m ahead, 3 m to the left, walking right at 1.5 m/s: inside from 1.0 s
    c = _conflict(EgoMotion(8.0, 0.0, 0.5, 0.05, True),
                  [[12.0, 0.0, 3.0, -1.5], [12.0, 0.0, 6.0, 0.0], [-5.0, 0.0, 0.0, 0.0]])
    # the ego's own sideways spread (0.8 m at 2 s) and the pedestrian's keep it below 1
    assert c.probability[0] > 0.75 and c.time_s[0] == pytest.approx(1.1, abs=0.25)
    assert c.probability[1] < 0.01 and c.probability[2] < 0.01  # on the sidewalk; behind the ego
    assert c.time_s[1] == 2.0 and c.time_std_s[1] == 0.0
    assert c.closest_m[0] < 5.0 and 0 <= c.closest_time_s[0] <= 2.0
    assert all(np.isfinite(getattr(c, f)).all() for f in c.__dataclass_fields__)


def test_a_standing_ego_only_its_front():
    c = _conflict(EgoMotion(0.0, 0.0, 0.5, 0.05, True), [[1.5, 0.0, 0.2, 0.0], [8.0, 0.0, 0.0, 0.0]])
    assert c.probability[0] > 0.9 and c.probability[1] < 0.01


def test_a_reversing_ego_looks_behind():
    c = _conflict(EgoMotion(-3.0, 0.0, 0.5, 0.05, True), [[-4.0, 0.0, 0.0, 0.0], [4.0, 0.0, 0.0, 0.0]])
    assert c.probability[0] > 0.9 and c.probability[1] < 0.01


def test_a_turning_ego_meets_the_pedestrian_on_its_arc():
    motion = EgoMotion(8.0, 0.4, 0.5, 0.05, True)  # radius 20 m, turning left
    on_arc = [20 * np.sin(0.6), 20 * (1 - np.cos(0.6))]
    straight = [12.0, -1.0]
    c = _conflict(motion, [[on_arc[0], 0, on_arc[1], 0], [straight[0], 0, straight[1], 0]])
    assert c.probability[0] > 0.9 and c.probability[1] < 0.1
    s, d, _ = path_coordinates(predict_ego_path(EgoPose.from_xy_yaw(0, 0, 0), motion, TIMES), np.array([on_arc]))
    assert s[0] == pytest.approx(12.0, abs=0.01) and abs(d[0]) < 1e-6


def test_wide_uncertainty_lowers_the_probability():
    sure = _conflict(EgoMotion(8.0, 0.0, 0.5, 0.05, True), [[12.0, 0.0, 3.5, 0.0]], std=0.2)
    unsure = _conflict(EgoMotion(8.0, 0.0, 0.5, 0.05, True), [[12.0, 0.0, 3.5, 0.0]], std=5.0)
    assert sure.probability[0] < 0.1 and 0.15 < unsure.probability[0] < 0.6


@pytest.mark.parametrize("beyond, across, inside", [
    (1.0, 0.0, True),    # 1 m past the corridor's straight end, on the path: within its round end
    (1.4, 1.4, False),   # past the end and to the side: 2 m from the end point
    (-1.0, 1.2, True),   # before the end, 1.2 m to the side
])
def test_the_corridor_ends_in_a_half_disc(beyond, across, inside):
    # a standing ego at 0 covers nothing: the corridor is its front, 2.5 m, then the round end of 1.5 m
    c = _conflict(EgoMotion(0.0, 0.0, 0.0, 0.0, True), [[2.5 + beyond, 0.0, across, 0.0]], std=0.05)
    assert c.probability[0] > 0.9 if inside else c.probability[0] < 0.5  # (the position spreads over 2 s)


def test_the_coordinates_and_normal_of_a_turning_path():
    motion = EgoMotion(8.0, 0.4, 0.5, 0.05, True)  # radius 20 m, turning left: the normal points inwards
    path = predict_ego_path(EgoPose.from_xy_yaw(0, 0, 0), motion, TIMES)
    points = np.array([[0.0, 1.0], [0.0, -1.0], [20 * np.sin(0.6), 20 * (1 - np.cos(0.6))]])
    s, d, normal = path_coordinates(path, points)
    assert s[:2] == pytest.approx([0.0, 0.0], abs=1e-9) and d[:2] == pytest.approx([1.0, -1.0], abs=1e-9)
    assert np.allclose(normal[0], [0.0, 1.0]) and np.allclose(normal[2], [-np.sin(0.6), np.cos(0.6)])


def test_pedestrians_behind_or_beyond_the_corridor_at_every_step_are_exactly_out():
    # a standing ego: the corridor reaches 2.5 + 1.5 m ahead. Behind it (walking away), beyond it
    # (walking along) and 10 m to the side: when all are out at every step the Gaussian work is skipped,
    # and the answer is what the full computation gives them beside a pedestrian in front (no skip)
    standing = EgoMotion(0.0, 0.0, 0.5, 0.05, True)
    out = [[-1.0, -1.0, 0.3, 0.0], [4.3, 1.5, -0.5, 0.0], [30.0, -0.5, 10.0, 0.0]]
    alone = _conflict(standing, out)
    beside = _conflict(standing, out + [[1.5, 0.0, 0.2, 0.0]])
    assert (alone.probability == 0.0).all() and (alone.time_s == 2.0).all() and (alone.time_std_s == 0.0).all()
    for f in alone.__dataclass_fields__:
        assert np.array_equal(getattr(alone, f), getattr(beside, f)[:3]), f
    assert beside.probability[3] > 0.9


def test_a_pedestrian_passing_through_the_corridor_lengthwise_is_not_skipped():
    # behind the standing ego's front at the first step and beyond its reach (4 m) at the last:
    # on the path in between, so inside, although both ends are out
    c = _conflict(EgoMotion(0.0, 0.0, 0.5, 0.05, True), [[-1.0, 3.0, 0.0, 0.0]])
    assert c.probability[0] > 0.9 and 0.0 < c.time_s[0] < 1.0


def test_a_person_standing_on_the_sidewalk_is_not_flagged_with_the_corridor_spread():
    # the KITTI drives' typical false alarm: the ego at 6 m/s, a person standing 10 m ahead 2.4 m to
    # the side (0.9 m beyond the corridor's edge). The track filter's 1 m/s^2 spreads them 2 m at 2 s
    # and flags them; the corridor's spread (calibrated on the drives' labels) does not
    ego, person = EgoMotion(6.0, 0.0, 0.5, 0.05, True), [[10.0, 0.0, -2.4, 0.0]]
    wide = _conflict(ego, person, std=0.2, acceleration_std=1.0).probability[0]
    corridor = _conflict(ego, person, std=0.2, acceleration_std=CORRIDOR_ACCELERATION_STD_MPS2).probability[0]
    assert wide >= CONFLICT_PROBABILITY and corridor < 0.2
    # one walking into the path is still flagged with it
    crossing = _conflict(ego, [[10.0, 0.0, -2.4, 1.4]], std=0.2, acceleration_std=CORRIDOR_ACCELERATION_STD_MPS2)
    assert crossing.probability[0] > 0.9
