"""Motion state: hysteresis between standing, walking and running."""

import numpy as np

from pedenv.behaviour.config import BehaviourConfig
from pedenv.behaviour.motion_state import RUNNING, STANDING, WALKING, next_state, speed_and_std

CFG = BehaviourConfig(enabled=True)


def test_hysteresis_does_not_flicker():
    speeds = [0.0, 0.5, 0.9, 0.5, 0.4, 0.25, 0.5, 3.5, 2.5, 2.0]
    state, out = np.array([STANDING], np.int8), []
    for v in speeds:
        state = next_state(state, np.array([v]), np.array([0.05]), CFG)
        out.append(int(state[0]))
    # a sprint from standing goes straight to running; 2.5 m/s still runs (exit 2.3), 2.0 walks
    assert out == [STANDING, STANDING, WALKING, WALKING, WALKING, STANDING, STANDING, RUNNING, RUNNING, WALKING]


def test_an_uncertain_speed_does_not_start_walking():
    state = next_state(np.array([STANDING], np.int8), np.array([1.0]), np.array([0.5]), CFG)
    assert state[0] == STANDING


def test_speed_and_std_at_standstill_uses_the_widest_axis():
    speed, std = speed_and_std(np.zeros((1, 2)), np.array([[[0.04, 0.0], [0.0, 0.09]]]))
    assert speed[0] == 0 and np.isclose(std[0], 0.3)
