"""The static camera fitted to people seen by a known camera: rendered upright people, the
built-in static scene through the detector model, and the refusals."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.body import ANKLE, EAR, EYE
from pedenv.calibration.fit import estimate_camera
from pedenv.calibration.geometry import camera_rotation, intrinsics, parameters_of, project, static_camera
from pedenv.calibration.linking import BoxLinker
from pedenv.calibration.observations import Observations, observations_of
from pedenv.calibration.refusals import CalibrationRefused


def _people(focal: float, height: float, tilt_deg: float, roll_deg: float = 0.0, *, n: int = 400,
            ranges: tuple[float, float] = (6.0, 50.0), seed: int = 0) -> Observations:
    """Upright people of random heights (1.72 m, 0.09 m) standing in front of a 1600x900 camera."""
    rng = np.random.default_rng(seed)
    k, r = intrinsics(focal, (800.0, 450.0)), camera_rotation(np.radians(tilt_deg), np.radians(roll_deg))
    xy = np.c_[rng.uniform(*ranges, n), rng.uniform(-15.0, 15.0, n)]
    tall = rng.normal(1.72, 0.09, n)
    feet = project(np.c_[xy, ANKLE * tall], k, r, height) + rng.normal(0.0, 1.0, (n, 2))
    heads = project(np.c_[xy, EYE * tall], k, r, height) + rng.normal(0.0, 1.0, (n, 2))
    seen = np.isfinite(feet).all(axis=1) & (feet[:, 0] > 0) & (feet[:, 0] < 1600) & (feet[:, 1] < 900) \
        & (heads[:, 1] > 0) & (feet[:, 1] - heads[:, 1] > 24)
    m = int(seen.sum())
    return Observations(feet[seen], heads[seen], np.full(m, EYE), np.arange(m), np.zeros(m, int))


@pytest.mark.parametrize(("focal", "height", "tilt_deg", "roll_deg"), [
    (1266.4, 6.0, 20.0, 0.0), (900.0, 3.0, 12.0, 2.0), (1500.0, 10.0, 35.0, -1.5)])
def test_rendered_people_give_the_camera(focal: float, height: float, tilt_deg: float, roll_deg: float) -> None:
    est = estimate_camera(_people(focal, height, tilt_deg, roll_deg), (1600, 900))
    assert est.focal == pytest.approx(focal, rel=0.05)
    assert est.height == pytest.approx(height, rel=0.05)
    assert np.degrees(est.tilt) == pytest.approx(tilt_deg, abs=1.0)
    assert np.degrees(est.roll) == pytest.approx(roll_deg, abs=0.5)
    errors = np.array([est.focal - focal, est.height - height, est.tilt - np.radians(tilt_deg)])
    assert np.all(np.abs(errors) < 4.0 * est.std[:3])  # the stated spread covers the error


def test_the_static_scene_through_the_detector_model() -> None:
    from pedenv.synthetic.detector import DetectorModel
    from pedenv.synthetic.generator import generate_scenes

    scene = generate_scenes(0, ["static-plaza"])[0]
    detector, linker, parts = DetectorModel(0), BoxLinker(), []
    for frame in scene.frames:
        det = detector(frame)
        parts.append(observations_of(det, frame.index, linker(det.boxes)))
    truth = parameters_of(scene.frames[0].camera)
    est = estimate_camera(Observations.concat(parts), (1600, 900))
    assert est.focal == pytest.approx(truth[0], rel=0.05)
    assert est.height == pytest.approx(truth[1], rel=0.05)
    assert np.degrees(est.tilt - truth[2]) == pytest.approx(0.0, abs=1.0)
    camera = est.camera()
    assert camera.static and camera.cam_to_vehicle[2, 3] == pytest.approx(est.height)


def test_the_walkers_exact_skeletons_give_the_camera() -> None:
    """The walkers' own 3D skeletons projected exactly, linked by box overlap: the head point on the
    body's axis (the ears) and the walker's stride (ankles up, head down) leave no bias; with the
    eyes as the head point the facing of standing people tilted the fit (focal +2.1 %, tilt -0.45 deg,
    height +3.1 % on this scene)."""
    from pedenv.pose.ground_truth import GroundTruthPose
    from pedenv.synthetic.generator import generate_scenes

    scene = generate_scenes(0, ["static-plaza"])[0]
    pose, linker, parts = GroundTruthPose(), BoxLinker(), []
    for frame in scene.frames:
        det = pose(frame)
        parts.append(observations_of(det, frame.index, linker(det.boxes)))
    obs = Observations.concat(parts)
    assert np.all(obs.head_share == EAR)  # every exact skeleton's ears are seen
    truth = parameters_of(scene.frames[0].camera)
    est = estimate_camera(obs, (1600, 900), walking=True)
    assert est.focal == pytest.approx(truth[0], rel=0.01)
    assert est.height == pytest.approx(truth[1], rel=0.02)
    assert np.degrees(est.tilt - truth[2]) == pytest.approx(0.0, abs=0.15)


def test_the_head_point_is_the_ears_else_the_eyes() -> None:
    from pedenv.body import STANDING
    from pedenv.records import Detections
    from pedenv.skeleton import CocoKeypoint as KP

    k, r = intrinsics(1266.4, (800.0, 450.0)), camera_rotation(np.radians(20.0), 0.0)
    body = STANDING * 1.72 + np.array([15.0, 0.0, 0.0])  # facing away from the camera, 15 m ahead
    kp = np.repeat(project(body, k, r, 6.0)[None], 2, axis=0)
    conf = np.ones((2, 17))
    conf[1, KP.LEFT_EAR] = 0.1  # one ear hidden: the eyes
    obs = observations_of(Detections(kp, conf))
    ears, eyes = kp[0, [KP.LEFT_EAR, KP.RIGHT_EAR]].mean(axis=0), kp[1, [KP.LEFT_EYE, KP.RIGHT_EYE]].mean(axis=0)
    np.testing.assert_allclose(obs.heads, [ears, eyes])
    np.testing.assert_allclose(obs.head_share, [EAR, EYE])


def test_a_level_camera_at_eye_height_asks_for_the_field_of_view() -> None:
    obs = _people(1266.4, 1.6, 0.0, ranges=(4.0, 40.0))
    with pytest.raises(CalibrationRefused, match="fov_deg"):
        estimate_camera(obs, (1600, 900))
    given = estimate_camera(obs, (1600, 900), focal=1266.4)  # with the focal length the rest is fixed
    assert given.height == pytest.approx(1.6, rel=0.05) and abs(np.degrees(given.tilt)) < 0.5
    assert given.focal_given and given.std[0] == 0.0


@pytest.mark.parametrize(("obs", "message"), [
    (Observations.empty(), "too few upright people"),
    (_people(1266.4, 6.0, 20.0, n=400, ranges=(20.0, 20.5)), "one row"),
])
def test_refusals_name_what_is_missing(obs: Observations, message: str) -> None:
    with pytest.raises(CalibrationRefused, match=message):
        estimate_camera(obs, (1600, 900))


def test_geometry_round_trip() -> None:
    camera = static_camera(1000.0, 4.0, np.radians(15.0), np.radians(-2.0), (1280, 720))
    f, h, tilt, roll = parameters_of(camera)
    assert (f, h) == pytest.approx((1000.0, 4.0))
    assert np.degrees([tilt, roll]) == pytest.approx([15.0, -2.0])


def test_the_stated_spread_widens_the_fits_own_and_holds_the_crowds_height(monkeypatch: pytest.MonkeyPatch) -> None:
    import pedenv.calibration.refusals as refusals
    from pedenv.calibration.fit import CROWD_MEAN_STD_M, FIT_STD_SCALE, PERSON_HEIGHT_MEAN_M

    obs = _people(1266.4, 6.0, 20.0, n=1000)
    est = estimate_camera(obs, (1600, 900))
    crowd = est.height * CROWD_MEAN_STD_M / PERSON_HEIGHT_MEAN_M
    assert crowd < est.std[1] < crowd * 1.3  # a thousand people: the crowd's mean height is most of it
    own = est.std[0] / FIT_STD_SCALE  # the focal length has no crowd term
    monkeypatch.setattr(refusals, "MAX_FOCAL_RELATIVE_STD", 1.2 * own / est.focal)  # below the stated 1-sigma
    assert estimate_camera(obs, (1600, 900)).focal == pytest.approx(est.focal)  # the people fix it: kept
    monkeypatch.setattr(refusals, "MAX_FOCAL_RELATIVE_STD", 0.8 * own / est.focal)
    with pytest.raises(CalibrationRefused, match="too close to parallel"):
        estimate_camera(obs, (1600, 900))
