"""The behaviour cues inside the model: every field finite on a synthetic scene, none with the
paper's method, and a defined answer after a gap of seconds."""

import dataclasses
import json

import numpy as np
import pytest

from pedenv.behaviour import estimator, motion_state
from pedenv.behaviour import heading_filter as hf
from pedenv.config import Config
from pedenv.model import PedestrianEnvironmentModel
from pedenv.outputs.jsonl import environment_line
from pedenv.records import EgoPose
from pedenv.synthetic import generate_scenes
from pedenv.synthetic.detector import DetectorModel


@pytest.fixture(scope="module")
def frames():
    scene = generate_scenes(0, ["red-light-crossing"], duration_s=4.0)[0]
    detector = DetectorModel(0)
    return [dataclasses.replace(f, detections=detector(f)) for f in scene.frames]


def test_every_field_is_finite_and_shaped(frames):
    model = PedestrianEnvironmentModel(Config())
    for frame in frames:
        state = model.update(frame)
        b, n = state.pedestrians.behaviour, len(state.pedestrians)
        assert b is not None and len(b) == n
        assert b.predicted_positions.shape == (n, 4, 2) and b.predicted_covariances.shape == (n, 4, 2, 2)
        for name in b.__dataclass_fields__:
            assert np.isfinite(np.asarray(getattr(b, name), float)).all(), name
    line = json.loads(environment_line(state))
    assert line["pedestrians"][0]["behaviour"]["orientation_availability"] in hf.AVAILABILITY_NAMES
    assert line["ego_motion"]["speed"] >= 0 and len(line["ego_motion"]["path"]) == 21


def test_the_paper_method_has_no_behaviour(frames):
    model = PedestrianEnvironmentModel(Config(method="paper"))
    state = model.update(frames[0])
    assert model.behaviour is None and state.pedestrians.behaviour is None
    assert "behaviour" not in json.dumps(state.to_dict())


def test_a_gap_of_seconds_widens_the_orientation(frames):
    model = PedestrianEnvironmentModel(Config())
    for frame in frames[:20]:
        before = model.update(frame).pedestrians.behaviour
    later = dataclasses.replace(frames[20], timestamp=frames[19].timestamp + 6.0)
    after = model.update(later).pedestrians.behaviour
    assert np.median(after.yaw_std) >= np.median(before.yaw_std)
    assert after.ego_speed == 0.0  # the ego's motion is forgotten, not extrapolated over the gap
    assert all(np.isfinite(np.asarray(getattr(after, f), float)).all() for f in after.__dataclass_fields__)


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1e300])
def test_a_broken_filter_state_gets_a_wide_defined_answer(frames, bad):
    model = PedestrianEnvironmentModel(Config())
    state = model.update(frames[0])
    n = len(state.pedestrians)
    x, P = np.full((n, 4), bad), np.full((n, 4, 4), bad)
    model.behaviour.reset()
    peds = model.behaviour.update(frames[1], dataclasses.replace(state.pedestrians, behaviour=None), x, P,
                                  np.ones(n, bool), state.pedestrians.track_ids)
    b = peds.behaviour
    assert all(np.isfinite(np.asarray(getattr(b, f), float)).all() for f in b.__dataclass_fields__)
    assert np.allclose(b.predicted_positions[:, 0], state.pedestrians.positions[:, :2])  # standing where reported


def test_an_implausibly_fast_track_enters_the_corridor_at_most_that_fast(frames, monkeypatch):
    # an ego driving along +x at 8 m/s; a pedestrian 12 m ahead and 11.5 m to its left: a filter saying
    # 10 m/s towards the path; the corridor moves at the speed posterior's mean velocity, which the grid's
    # fastest speed bounds (5 m/s: 1.5 m from the path at 2 s); at the 4 m/s cap it is still 3.5 m away
    state = PedestrianEnvironmentModel(Config()).update(frames[0])
    peds, n = dataclasses.replace(state.pedestrians, behaviour=None), len(state.pedestrians)
    t = frames[0].timestamp
    now = dataclasses.replace(frames[0], ego=EgoPose.from_xy_yaw(0.0, 0.0, 0.0))
    x = np.tile([-50.0, 0.0, 0.0, 0.0], (n, 1))  # the others stand behind the ego
    x[0] = [12.0, 0.0, 11.5, -10.0]
    P = np.repeat(np.diag([0.01, 0.01, 0.01, 0.01])[None], n, axis=0)
    answers = []
    for cap in (15.0, 4.0):
        monkeypatch.setattr(estimator, "MAX_PEDESTRIAN_SPEED_MPS", cap)
        est = PedestrianEnvironmentModel(Config()).behaviour
        for k in range(5, 0, -1):
            est.ego.add(t - 0.1 * k, EgoPose.from_xy_yaw(-0.8 * k, 0.0, 0.0))
        b = est.update(now, peds, x, P, np.ones(n, bool), peds.track_ids).behaviour
        answers.append(b.conflict_probability[0])
        # the reported path: not capped by the corridor's cap; it moves at the speed posterior's mean velocity,
        # which the grid's fastest speed bounds (5 m/s; the likelihood's heavy tail leaves a little of the
        # posterior below it: 4.93 m/s measured)
        top = motion_state.SPEED_GRID_MPS[-1]
        assert b.predicted_positions[0, -1, 0] == pytest.approx(12.0, abs=1e-3)
        assert 11.5 - 3.0 * top - 1e-3 <= b.predicted_positions[0, -1, 1] <= 11.5 - 3.0 * (top - 0.2)
    assert b.ego_speed == pytest.approx(8.0)
    assert answers[0] > 0.4 and answers[1] < 0.05, answers  # measured 0.50 and 0.025


def test_the_orientation_interval_holds_the_orientation_between_updates(frames):
    model = PedestrianEnvironmentModel(Config().replace(behaviour={"orientation_interval_s": 0.3}))
    every = PedestrianEnvironmentModel(Config().replace(behaviour={"orientation_interval_s": 0.0}))
    held: dict = {}
    for k, frame in enumerate(frames[:12]):  # 10 Hz: the grids are updated at frames 0, 3, 6 and 9
        peds, reference = model.update(frame).pedestrians, every.update(frame).pedestrians.behaviour
        b = peds.behaviour
        assert np.array_equal(b.predicted_positions, reference.predicted_positions)  # the rest: every frame
        assert np.array_equal(b.motion_state, reference.motion_state)
        assert all(np.isfinite(np.asarray(getattr(b, f), float)).all() for f in b.__dataclass_fields__)
        now = {t: (b.yaw[i], b.yaw_std[i], b.facing_probability[i], b.head_facing_probability[i],
                   b.orientation_availability[i]) for i, t in enumerate(peds.track_ids.tolist())}
        if k == 0:
            assert np.array_equal(b.yaw, reference.yaw) and np.array_equal(b.yaw_std, reference.yaw_std)
        if k % 3 == 0:
            held.update(now)
            continue
        for track, values in now.items():
            if track in held:
                assert values == held[track]  # as at its last update
            else:
                assert values[1] > 1.8 and values[4] == hf.UNAVAILABLE  # new since: nothing known yet


def test_far_but_valid_states_are_used_as_they_are(frames):
    # positions of 9e5 m: every entry within the limit (1e6 m), their sum of squares beyond its square,
    # so the rows are checked one by one; all are usable and the path is the state's, not the reported
    state = PedestrianEnvironmentModel(Config()).update(frames[0])
    peds, n = dataclasses.replace(state.pedestrians, behaviour=None), len(state.pedestrians)
    x = np.tile([9e5, 1.0, -9e5, 0.5], (n, 1))
    P = np.repeat(np.diag([0.1, 0.2, 0.1, 0.2])[None], n, axis=0)
    est = PedestrianEnvironmentModel(Config()).behaviour
    b = est.update(frames[1], peds, x, P, np.ones(n, bool), peds.track_ids).behaviour
    assert np.vdot(x, x) > 1e12
    assert np.allclose(b.predicted_positions[:, -1], [9e5 + 3.0, -9e5 + 1.5])  # 3 s ahead at (1, 0.5) m/s
    assert np.allclose(b.speed, np.hypot(1.0, 0.5))
