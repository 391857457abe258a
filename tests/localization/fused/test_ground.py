import numpy as np
import pytest

from pedenv.config import FusedConfig
from pedenv.geometry import pixel_rays
from pedenv.localization.fused import ground as ground_module
from pedenv.localization.fused.ground import ground_cue, plane_intersection
from pedenv.skeleton import ANKLE_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP

from fused_frames import make_frame, skeletons_of

#: The frames' exact skeletons have their ankles at the anatomical height: no pose-network offset.
FAR = FusedConfig(ground_max_distance_m=60.0, ankle_keypoint_offset_m=0.0)


def run_ground(frame, config=FAR, noise_px=None):
    return ground_cue(frame, skeletons_of(frame, config, noise_px), config)


def set_model(monkeypatch, **constants):
    """The ground cue's model constants (``ROAD_HEIGHT_STD_M=0.0``, ...) changed for one test."""
    for name, value in constants.items():
        assert hasattr(ground_module, name), name
        monkeypatch.setattr(ground_module, name, value)


@pytest.mark.parametrize("pitch, roll", [(0.0, 0.0), (0.03, 0.0), (-0.03, 0.02)])
def test_ground_point_on_a_slope_seen_from_a_pitched_vehicle(pitch, roll):
    # the road is the vehicle's plane: on a slope the vehicle pitches with it
    ground = np.array([[6.0, 1.0, 0.0], [12.0, -2.5, 0.0], [25.0, 3.0, 0.0]])
    from pedenv.geometry import rotation_from_ypr
    normal = rotation_from_ypr(0.0, pitch, roll)[:, 2]
    ground[:, 2] = -(ground[:, :2] @ normal[:2]) / normal[2]  # on the vehicle's plane z_vehicle = 0
    cue = run_ground(make_frame(ground, pitch=pitch, roll=roll))
    assert cue.valid.all()
    np.testing.assert_allclose(cue.positions, ground[:, :2], atol=0.02)


def test_ground_variance_grows_fast_with_distance():
    ground = np.array([[5.0, 0.0, 0.0], [10.0, 0.0, 0.0], [20.0, 0.0, 0.0], [40.0, 0.0, 0.0]])
    cue = run_ground(make_frame(ground))
    total = cue.covariances + cue.bias_covariances
    along, across = total[:, 0, 0], total[:, 1, 1]
    assert np.all(np.diff(along) > 0)
    assert along[3] / along[0] > 8 ** 2  # faster than the square of the distance
    assert np.all(along > across)  # wide along the ray, tight across it


def test_pixel_jacobian_matches_finite_differences(monkeypatch):
    set_model(monkeypatch, ROAD_HEIGHT_STD_M=0.0, ROAD_CURVATURE_STD_PER_M=0.0, ANKLE_HEIGHT_STD_M=0.0,
              LATERAL_STD_M=0.0, STANCE_STD_M=0.0)
    config = FusedConfig(ground_max_distance_m=60.0, keypoint_pixel_std=1.0, ankle_keypoint_offset_m=0.0)
    frame = make_frame(np.array([[15.0, 2.0, 0.0]]), pitch=0.02, roll=0.01)
    cue = run_ground(frame, config, noise_px=1.0)
    kp = frame.detections.keypoints[0, list(ANKLE_KEYPOINTS)]
    normal = frame.ego.rotation[:, 2]
    offset = float(normal @ frame.ego.translation) + 0.046 * 1.72
    jac = []
    for axis in (0, 1):
        step = np.zeros(2)
        step[axis] = 1e-3
        ends = [plane_intersection(pixel_rays(kp + s * step, frame.camera.intrinsics, frame.cam_to_world),
                                   frame.cam_to_world[:3, 3], normal, offset)[0][:, :2] for s in (1, -1)]
        jac.append((ends[0] - ends[1]) / 2e-3)
    jac = np.stack(jac, axis=-1)  # (2 ankles, 2, 2)
    expected = np.einsum("aij,akj->ik", jac, jac) / 4.0  # mean of two independent ankles
    np.testing.assert_allclose(cue.covariances[0], expected, rtol=1e-3)
    assert np.allclose(cue.bias_covariances, 0.0)  # no road spread: nothing repeats per person


def test_the_road_height_is_the_per_person_part(monkeypatch):
    set_model(monkeypatch, ROAD_HEIGHT_STD_M=0.2, LATERAL_STD_M=0.0)
    cue = run_ground(make_frame(np.array([[12.0, 2.0, 0.0]])), FusedConfig())
    vals, vecs = np.linalg.eigh(cue.bias_covariances[0])
    assert vals[0] < 1e-9 * vals[1]  # along the ray only
    assert abs(vecs[:, 1] @ np.array([12.0, 0.5]) / np.hypot(12.0, 0.5)) > 0.99


def test_where_the_feet_stand_against_the_body_is_the_per_person_part(monkeypatch):
    """The lateral spread (lean, stance) repeats over a gait cycle: the filter must not
    average it away, so it is per-person, not frame-to-frame (near people's sideways
    errors were 1.8x their reported variance on the terrain scenes with it frame-to-frame)."""
    frame = make_frame(np.array([[12.0, 2.0, 0.0]]))
    set_model(monkeypatch, ROAD_HEIGHT_STD_M=0.0, ROAD_CURVATURE_STD_PER_M=0.0, LATERAL_STD_M=0.0)
    plain = run_ground(frame, FusedConfig())
    set_model(monkeypatch, LATERAL_STD_M=0.05)
    lateral = run_ground(frame, FusedConfig())
    np.testing.assert_allclose(lateral.covariances, plain.covariances)
    np.testing.assert_allclose(lateral.bias_covariances[0], 0.05**2 * np.eye(2), atol=1e-12)


@pytest.mark.parametrize("hidden, share", [((), 0.25), ((KP.LEFT_ANKLE,), 1.0)])
def test_a_lone_standing_foot_may_lie_half_a_step_from_the_body(hidden, share, monkeypatch):
    """Frame to frame, the ground point of one standing foot spreads by STANCE_STD_M each way
    about the body's; the midpoint of two standing feet by half of it."""
    frame = make_frame(np.array([[12.0, 2.0, 0.0]]), hidden=hidden)
    set_model(monkeypatch, STANCE_STD_M=0.0, ANKLE_HEIGHT_STD_M=0.0)
    plain = run_ground(frame, FusedConfig())
    set_model(monkeypatch, STANCE_STD_M=0.14)
    stance = run_ground(frame, FusedConfig())
    np.testing.assert_allclose(stance.covariances[0] - plain.covariances[0], share * 0.14**2 * np.eye(2), atol=1e-12)
    np.testing.assert_allclose(stance.bias_covariances, plain.bias_covariances)


@pytest.mark.parametrize("case, reason", [
    ("no-ankles", "no-ankles"),
    ("above-horizon", "above-horizon"),
    ("camera-below-road", "camera-below-road"),
    ("far", "beyond-range"),
])
def test_ground_declines_with_a_reason(case, reason):
    if case == "no-ankles":
        frame = make_frame(np.array([[10.0, 0.0, 0.0]]), hidden=ANKLE_KEYPOINTS)
    elif case == "above-horizon":  # a person on a rise far above the vehicle's plane
        frame = make_frame(np.array([[30.0, 0.0, 3.0]]))
    elif case == "camera-below-road":  # the vehicle's origin (its road) lies above the camera
        frame = make_frame(np.array([[10.0, 0.0, 0.0]]), ego_xyz=(0.0, 0.0, 0.0))
        from dataclasses import replace

        from pedenv.records import EgoPose
        ego = EgoPose(np.array([0.0, 0.0, 2.0]), frame.ego.rotation)
        frame = replace(frame, ego=ego, camera=frame.camera)
        frame = replace(frame, camera=type(frame.camera).from_fov(1600, 900, 64.5, height_m=-1.0))
    else:
        frame = make_frame(np.array([[70.0, 0.0, 0.0]]))
    cue = run_ground(frame)
    assert not cue.valid[0]
    assert cue.reason_names[0] == reason
    assert np.isfinite(cue.positions).all() and np.isfinite(cue.covariances).all()


def test_ground_uses_the_stance_ankle_when_the_other_swings():
    from dataclasses import replace

    from pedenv.records import Detections
    frame = make_frame(np.array([[10.0, 1.0, 0.0]]))
    kp = frame.detections.keypoints.copy()
    kp[0, ANKLE_KEYPOINTS[0], 1] -= 0.15 * np.ptp(kp[0, :, 1])
    cue = run_ground(replace(frame, detections=Detections(kp, frame.detections.confidences)))
    assert cue.positions[0, 0] == pytest.approx(10.0, abs=0.05)  # range: the stance foot on the road
    assert cue.positions[0, 1] == pytest.approx(1.0, abs=0.12)  # across: that foot, not the midpoint
