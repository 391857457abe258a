"""Seeded fuzz of the model (issue 10): whatever detections arrive, update() either refuses
them with an InputError or returns only finite values within the method's maximum range.

Issue 19: small, collapsed, degenerate and far skeletons with ego motion and time steps,
the sequences of :mod:`pedenv.evaluation.fuzz` (a seeded share of the 100,000 that
``benchmarks/fuzz_update.py`` runs): no NaN or inf, no covariance that is not positive
semi-definite, no exception but InputError, no pedestrian made of a person with no seen keypoint, for both methods."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.evaluation import fuzz as fuzz_update
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame

from standing_people import frame_with_people

CAMERA = Camera.from_fov()
#: Sequences per method in CI (seeds 0, 2, 4, ... for paper, 1, 3, 5, ... for fused).
CI_SEQUENCES = 300
FIELDS = ("positions", "velocities", "covariances", "keypoints", "confidences", "boxes", "keypoints_3d", "distances")


def fuzz_detections(rng: np.random.Generator) -> Detections:
    """0-4 people whose keypoints are one of: plausible, random finite up to 1e300 px, partly NaN,
    tiny or huge skeletons; boxes from the keypoints, given (sometimes inverted), or none."""
    n = int(rng.integers(0, 5))
    kind = rng.integers(0, 6, n)
    centre = rng.uniform([0, 0], [1600, 900], (n, 1, 2))
    scale = 10.0 ** rng.uniform(-3, 3, (n, 1, 1))
    kp = centre + rng.normal(0, 1, (n, 17, 2)) * scale
    wild = kind == 1
    kp[wild] = rng.choice([-1, 1], (wild.sum(), 17, 2)) * 10.0 ** rng.uniform(-2, 300, (wild.sum(), 17, 2))
    near_out = kind == 2
    kp[near_out] = rng.uniform(-16000, 17600, (near_out.sum(), 17, 2))
    holes = rng.random((n, 17)) < np.where(kind == 3, 0.7, 0.05)[:, None]
    kp[holes] = np.nan
    conf = rng.random((n, 17))
    conf[rng.random((n, 17)) < 0.03] = np.nan
    boxes = None
    if rng.random() < 0.3:
        lo = rng.uniform(-100, 1700, (n, 2))
        boxes = np.column_stack([lo, lo + rng.uniform(-5, 300, (n, 2))])  # some inverted
    return Detections(kp, conf, boxes)


def fuzz_run(method: str, seed: int, frames: int = 40) -> tuple[int, int]:
    """Run a fuzzed sequence; returns (states checked, frames refused)."""
    rng = np.random.default_rng(seed)
    cfg = configure(Config(), method)
    model = PedestrianEnvironmentModel(cfg)
    checked = refused = 0
    t = 0.0
    for i in range(frames):
        t += float(rng.choice([1e-3, 0.1, 0.1, 0.5, 30.0]))
        ego = EgoPose.from_xy_yaw(2.0 * t, 0.1 * np.sin(t), 0.05 * t)
        try:
            det = fuzz_detections(rng)
            state = model.update(Frame(i, t, CAMERA, ego, detections=det))
        except InputError:
            refused += 1
            continue
        p = state.pedestrians
        for name in FIELDS:
            assert np.isfinite(getattr(p, name)).all(), (method, seed, i, name)
        if p.behaviour is not None:  # the behaviour cues (fused) are never NaN either
            for name in p.behaviour.__dataclass_fields__:
                assert np.isfinite(np.asarray(getattr(p.behaviour, name), float)).all(), (method, seed, i, name)
        origin = model.tracks.filter  # the filter's own state must stay finite too
        assert np.isfinite(origin.x).all() and np.isfinite(origin.P).all(), (method, seed, i)
        cam_xy = (ego.matrix @ CAMERA.cam_to_vehicle)[:2, 3]
        ranges = np.hypot(*(p.positions[:, :2] - cam_xy).T)
        assert (ranges <= model.max_range_m * (1 + 1e-9)).all(), (method, seed, i, ranges.max())
        assert np.isfinite(state.ego.translation).all()
        checked += 1
    return checked, refused


@pytest.mark.parametrize("method", ["paper", "fused"])
def test_fuzzed_detections_never_leave_nan_or_beyond_the_cap(method):
    checked = refused = 0
    for seed in range(12):
        c, r = fuzz_run(method, seed)
        checked, refused = checked + c, refused + r
    # both outcomes occur: the fuzz reaches the model and the refusals
    assert checked > 150 and refused > 50


def test_transition_cache_stays_bounded():
    """Issue 10.7: one cached (F, Q) per distinct frame interval grew without bound."""
    model = PedestrianEnvironmentModel()
    t = 0.0
    for i in range(150):  # through update(): 149 distinct intervals
        t += 0.05 + 1e-4 * i
        model.update(frame_with_people(i, t, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))
    info = model._transition.cache_info()
    assert info.maxsize == 64 and info.currsize == 64 and info.misses == 149
    for i in range(1000):  # 1000 more distinct intervals
        model._transition(round(0.2 + 1e-4 * i, 6))
    assert model._transition.cache_info().currsize == 64


@pytest.mark.parametrize("method", ["paper", "fused"])
def test_degenerate_skeletons_never_give_nan_a_bad_covariance_or_an_exception(method):
    """Issue 19: before its fixes these seeds gave fused 1 frame with NaN and 27 with a
    covariance not positive semi-definite (a collapsed skeleton's height cue at 1e16 m,
    1e55 m^2, broke the filter's arithmetic) and paper 354 frames with a pedestrian made of
    a person with no seen keypoint."""
    methods = ("paper", "fused")
    configs = {m: configure(Config(), m) for m in methods}
    out = fuzz_update.Outcome()
    for k in range(methods.index(method), 2 * CI_SEQUENCES, 2):
        out.add(fuzz_update.run_sequence(k, method, configs))
    assert out.sequences == CI_SEQUENCES and out.frames > 2 * CI_SEQUENCES
    assert (out.nan_frames, out.bad_covariance_frames, out.phantom_frames, dict(out.exceptions)) == (0, 0, 0, {}), \
        out.first_seed


#: The issue's two reproductions: one point repeated, ego 2 and 5 m/s; NaN at frame 1 and
#: ValueError from linear_sum_assignment before the fix.
COLLAPSED = [((1475.0, 202.0), 0.2), ((545.0, 482.0), 0.5)]


@pytest.mark.parametrize(("point", "step"), COLLAPSED)
def test_a_skeleton_collapsed_to_one_point_gives_no_position_from_its_height(point, step):
    model = PedestrianEnvironmentModel(Config())
    kp = np.full((1, 17, 2), point)
    for i in range(3):
        ego = EgoPose.from_xy_yaw(step * i, 0, 0)
        state = model.update(Frame(i, 0.1 * i, CAMERA, ego, detections=Detections(kp, np.full((1, 17), 0.9))))
        p = state.pedestrians
        assert len(p) == 1 and np.isfinite(p.positions).all() and np.isfinite(p.covariances).all()
        assert fuzz_update.psd(p.covariances) and fuzz_update.psd(model.tracks.filter.P[:, [0, 2]][:, :, [0, 2]])
        assert "height:inconsistent" in p.sources[0]  # a collapsed skeleton has no height to read


@pytest.mark.parametrize("kind", ["nan", "zero", "negative"])
def test_paper_leaves_out_a_person_with_no_seen_keypoint(kind):
    """Issue 19: the paper method placed them 479-500 m away; fused leaves them out too."""
    good = frame_with_people(0, 0.0, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]).detections
    kp, conf = good.keypoints.copy(), good.confidences.copy()
    ghost_kp, ghost_conf = kp[0] + [300.0, 0.0], {"nan": conf[0], "zero": 0 * conf[0], "negative": -conf[0]}[kind]
    if kind == "nan":
        ghost_kp = np.full_like(ghost_kp, np.nan)
    det = Detections(np.stack([kp[0], ghost_kp]), np.stack([conf[0], ghost_conf]))
    for method in ("paper", "fused"):
        model = PedestrianEnvironmentModel(configure(Config(), method))
        state = model.update(Frame(0, 0.0, CAMERA, EgoPose.from_xy_yaw(0, 0, 0), detections=det))
        assert len(state.pedestrians) == 1 and state.pedestrians.distances[0] < 30.0, method
