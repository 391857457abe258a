"""The paper's position estimate on synthetic people at known distances."""

import numpy as np
import pytest

from pedenv.config import Config, PaperConfig
from pedenv.geometry import invert_transform, project
from pedenv.localization.paper import (
    HEIGHT_FIRST,
    HEIGHT_PARALLEL,
    TRIANGULATION,
    Reprojection,
    Sighting,
    estimate_positions,
    keep_most_confident,
    refine_distance,
)
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import EgoPose, Frame

from standing_people import frame_with_people


def _geometry(camera, target):
    frame = Frame(0, 0.0, camera, EgoPose.from_xy_yaw(0, 0, 0))
    c2w = frame.cam_to_world
    origin = c2w[:3, 3]
    centre = np.array([target[0], target[1], 0.85])
    d = np.linalg.norm(centre - origin)
    return origin, invert_transform(c2w), ((centre - origin) / d)[None], d


def test_keep_most_confident_drops_thirty_percent():
    conf = np.linspace(0.1, 0.9, 17)[None]
    keep = keep_most_confident(np.ones((1, 17), bool), conf, 0.3)
    assert keep.sum() == 12  # 17 - floor(0.3 * 17)
    assert not keep[0, :5].any() and keep[0, 5:].all()


@pytest.mark.parametrize("start_factor", [0.6, 1.5])
def test_refinement_removes_three_quarters_of_the_error(camera, start_factor):
    """Pixel height ~ 1/depth, so each step multiplies the error by (1 - 1/lambda): 5/20 in all."""
    origin, w2c, direction, d_true = _geometry(camera, (30.0, 0.0))
    cfg = PaperConfig()
    h_px = camera.intrinsics[1, 1] * 1.7 / 30.0  # a 1.7 m person at a depth of 30 m
    refined = refine_distance(np.array([start_factor * d_true]), direction, origin, np.array([h_px]),
                              Reprojection(camera.intrinsics, w2c, 0.0), cfg)
    assert refined[0] / d_true - 1 == pytest.approx((start_factor - 1) * 5 / 20, abs=2e-3)


def test_one_refinement_step_is_the_papers_rescaling(camera):
    """d * (1 + (h_est / h_orig - 1) / lambda), h_est the projected height of the person at d (Eq. 6-7)."""
    origin, w2c, direction, _ = _geometry(camera, (25.0, 4.0))
    cfg = PaperConfig()
    d0, h_orig, lam = 20.0, 80.0, 3.0
    bottom = origin + d0 * direction[0]
    bottom[2] = 0.0
    px, _ = project(np.stack([bottom, bottom + [0.0, 0.0, cfg.person_height_m]]), camera.intrinsics, w2c)
    h_est = np.linalg.norm(px[1] - px[0])
    got = refine_distance(np.array([d0]), direction, origin, np.array([h_orig]),
                          Reprojection(camera.intrinsics, w2c, 0.0), cfg, lambdas=np.array([lam]))
    assert got[0] == pytest.approx(d0 * (1 + (h_est / h_orig - 1) / lam), rel=1e-12)


@pytest.mark.parametrize("has_prev, source", [(False, HEIGHT_FIRST), (True, HEIGHT_PARALLEL)])
def test_height_fallback_finds_the_true_distance(camera, has_prev, source):
    """Without a usable second view the distance comes from the person's pixel height alone."""
    origin, w2c, direction, d_true = _geometry(camera, (42.0, 0.0))
    h_px = camera.intrinsics[1, 1] * 1.7 / 42.0  # a 1.7 m person at a depth of 42 m
    rays = np.broadcast_to(direction[:, None], (1, 17, 3))
    ones = np.ones((1, 17))
    # the previous view, when there is one, is the same: parallel rays, no intersection
    est = estimate_positions(Sighting(rays, direction, ones, origin), np.array([h_px]),
                             Sighting(rays, direction, ones, origin[None]), np.array([has_prev]),
                             Reprojection(camera.intrinsics, w2c, 0.0), PaperConfig())
    assert est.sources.tolist() == [source]
    assert est.distances[0] == pytest.approx(d_true, rel=1e-3)
    np.testing.assert_allclose(est.positions[0], [42.0, 0.0, 0.0], atol=0.05)


def test_driving_ego_triangulates_a_standing_person():
    model = PedestrianEnvironmentModel(Config(method="paper"))
    sources = []
    for i in range(10):
        state = model.update(frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(1.4 * i, 0, 0), [(40.0, 6.0)]))
        sources.append(state.pedestrians.sources[0])
    assert sources[0] == HEIGHT_FIRST and set(sources[1:]) == {TRIANGULATION}
    est = state.pedestrians.positions[0]
    truth_dist = np.hypot(40.0 - 12.6, 6.0)
    # skeleton from ankles to eyes is 0.89 of the body: the 1.7 m prior overshoots, refinement blends
    assert np.hypot(*(est[:2] - [40.0, 6.0])) / truth_dist < 0.12


def test_standing_ego_and_person_fall_back_to_height_without_nan():
    model = PedestrianEnvironmentModel(Config(method="paper"))
    for i in range(5):
        state = model.update(frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 1.0)]))
    p = state.pedestrians
    assert p.sources[0] == HEIGHT_PARALLEL
    assert np.isfinite(p.positions).all() and np.isfinite(p.keypoints_3d).all()
    assert np.hypot(*(p.positions[0, :2] - [20.0, 1.0])) < 0.2 * 20


def test_midpoint_and_no_refinement_ablations_run(camera):
    for changes in ({"initial_estimate": "midpoint"}, {"refine": False}):
        model = PedestrianEnvironmentModel(Config(method="paper").replace(paper=changes))
        for i in range(4):
            state = model.update(frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(1.4 * i, 0, 0), [(30.0, 3.0)]))
        assert state.pedestrians.sources[0] == TRIANGULATION
        assert np.hypot(*(state.pedestrians.positions[0, :2] - [30.0, 3.0])) < 3.0
