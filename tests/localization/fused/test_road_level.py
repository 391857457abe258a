import numpy as np
import pytest

from pedenv.config import Config
from pedenv.localization.fused.road_level import (
    CROWD_MEAN_STD_M,
    MAX_LEVEL_M,
    MEMORY_S,
    PRIOR_STD_M,
    RoadLevel,
    crowd_floor,
    level_measurements,
)
from pedenv.model import PedestrianEnvironmentModel

from fused_frames import make_frame


def test_the_level_is_the_peoples_mean_shrunk_by_the_prior_and_forgets():
    road = RoadLevel()
    assert road.level == 0.0
    road.update(0.0, np.full(4, 0.3), np.full(4, 0.1**2))
    assert road.level == pytest.approx(0.3 * 400 / (400 + PRIOR_STD_M**-2))
    information = road.information
    road.update(MEMORY_S, np.zeros(0), np.zeros(0))  # no one seen for a while
    assert road.information == pytest.approx(information / np.e)
    road.update(1.0, np.full(1, 2.0), np.full(1, 0.01**2))  # time went back: a new scene
    assert road.information == pytest.approx(1e4) and road.level == MAX_LEVEL_M  # clipped


def test_the_crowds_mean_height_bounds_the_level_however_many_are_seen():
    # 1.5 m above the plane, a crowd whose mean is one CROWD_MEAN_STD_M off the population's
    # reads as a level 1.5 * 0.08 / 1.72 = 7 cm off
    floor = crowd_floor(1.5, 1.72)
    assert floor == pytest.approx(1.5 * CROWD_MEAN_STD_M / 1.72)
    road = RoadLevel()
    assert road.estimate(floor) == (0.0, 0.0)  # no one seen: the plane stays, it adds no spread
    road.update(0.0, np.full(1000, 0.2), np.full(1000, 0.1**2))  # many people, 0.2 m up
    level, added = road.estimate(floor)
    k = PRIOR_STD_M**2 / (PRIOR_STD_M**2 + 1e-5 + floor**2)  # their mean's noise 0.1^2 / 1000
    assert level == pytest.approx(0.2 * k)  # a tall crowd cannot raise it to the people's mean
    assert level < road.level < 0.2
    assert added == pytest.approx(k**2 * (1e-5 + floor**2))


@pytest.mark.parametrize("height_range, ground_range, level", [(10.0, 10.0, 0.0), (8.0, 10.0, 0.3), (12.0, 10.0, -0.3)])
def test_the_feet_level_from_both_ranges(height_range, ground_range, level):
    # the ground cue at 10 m from a camera 1.5 m above the plane: feet the height cue puts at 8 m
    # stand 1.5 * (1 - 8 / 10) = 0.3 m above it
    levels, variances = level_measurements(np.array([height_range]), np.array([0.05**2]), np.array([ground_range]),
                                           np.array([0.02**2]), 1.5, 0.08)
    assert levels[0] == pytest.approx(level)
    ratio = height_range / ground_range
    assert variances[0] == pytest.approx((1.5 * ratio) ** 2 * (0.05**2 + 0.02**2) + 0.08**2)


def test_people_on_a_raised_pavement_raise_the_level_and_are_placed_better():
    # five people of the population's height on a 0.25 m pavement 6-12 m ahead: the ground cue
    # alone puts them 0.25 / 1.5 too far; the level learned from them brings it back as far as a
    # crowd of tall people could not have raised it (the crowd floor), and its spread covers the rest
    ground = np.array([[6.0, 2.0, 0.25], [8.0, 3.0, 0.25], [9.0, -2.5, 0.25], [11.0, 3.5, 0.25], [12.0, -3.0, 0.25]])
    config = Config(method="paper").replace(method="fused", fused={"ankle_keypoint_offset_m": 0.0})
    model = PedestrianEnvironmentModel(config)
    for i in range(30):
        model.update(make_frame(ground, index=i, timestamp=0.1 * i))
    assert model.locator.road.level == pytest.approx(0.25, abs=0.03)
    frame = make_frame(ground, index=30, timestamp=3.0)
    model.update(frame)
    cue = {q.name: q for q in model.locator.last_cues}["ground"]
    along = np.linalg.norm(cue.positions, axis=1) / np.linalg.norm(ground[:, :2], axis=1) - 1.0
    assert np.abs(along).max() < 0.10  # without the level: about 0.25 / (1.5 - ankle) = 19 % too far
    error = cue.positions - ground[:, :2]
    spread = np.einsum("ni,nij,nj->n", error, np.linalg.inv(cue.covariances + cue.bias_covariances), error)
    assert spread.max() < 4.0  # within 2 sigma
