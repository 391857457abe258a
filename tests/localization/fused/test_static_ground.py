"""The ground cue of a static camera: no 20 m limit, no road-height terms, its range from the foot point's
variance, widened by the calibration's own error; the ankle keypoint's offset above the anatomical ankle."""

import dataclasses

import numpy as np
import pytest

from pedenv.config import FusedConfig
from pedenv.errors import InputError
from pedenv.geometry import invert_transform, project
from pedenv.localization.fused import ground as ground_module
from pedenv.localization.fused.cue import LATERAL_STD_M
from pedenv.localization.fused.fusion import STATIC_TRUST_ORDER, TRUST_ORDER
from pedenv.localization.fused.ground import ankle_height, box_bottom_ranges, ground_cue, static_ground_variance
from pedenv.records import Camera, Detections, EgoPose, Frame
from pedenv.synthetic.scenarios import static_camera

from fused_frames import skeletons_of, upright_skeletons

#: People straight ahead of a camera 6 m up, 20 deg down, at these ranges (metres).
RANGES = np.array([10.0, 30.0, 60.0, 120.0])
#: An exactly known camera seeing exact skeletons: no calibration error, ankles at the anatomical height.
EXACT = FusedConfig(static_camera_tilt_std_deg=0.0, static_camera_height_std_m=0.0, ankle_keypoint_offset_m=0.0,
                    ankle_keypoint_offset_std_m=0.0)


def static_frame(mount: str, ranges=RANGES) -> Frame:
    cam = static_camera()
    cam = Camera(cam.intrinsics, cam.width, cam.height, cam.cam_to_vehicle, mount)
    ground = np.column_stack([ranges, np.linspace(-2.0, 2.0, len(ranges)), np.zeros(len(ranges))])
    ego = EgoPose(np.zeros(3), np.eye(3))
    frame = Frame(0, 0.0, cam, ego)
    px, depth = project(upright_skeletons(ground, np.full(len(ground), 1.72)), cam.intrinsics,
                        invert_transform(frame.cam_to_world))
    return dataclasses.replace(frame, detections=Detections(px, (depth > 0).astype(float)))


def run(frame: Frame, config: FusedConfig | None = None, noise_px: float = 1.0):
    config = config or FusedConfig()
    return ground_cue(frame, skeletons_of(frame, config, noise_px), config)


def test_vehicle_mount_stops_at_20_m_and_static_goes_on():
    vehicle = run(static_frame("vehicle"), EXACT)
    assert vehicle.valid.tolist() == [True, False, False, False]
    assert list(vehicle.reason_names[1:]) == ["beyond-range"] * 3
    static = run(static_frame("static"), EXACT)
    assert static.valid.all()
    truth = np.column_stack([RANGES, np.linspace(-2.0, 2.0, len(RANGES))])
    rel = np.linalg.norm(static.positions - truth, axis=1) / RANGES
    assert rel.max() < 0.01  # exact skeletons: the cut with the calibrated ground is right


def test_static_variance_is_the_foot_points_alone():
    config = EXACT
    static, vehicle = run(static_frame("static"), config), run(static_frame("vehicle"), config)
    # the per-person part along the ray holds the ground's unevenness only, not the road's height and curvature
    assert static.bias_covariances[0, 0, 0] < vehicle.bias_covariances[0, 0, 0]
    no_ground = run(static_frame("static"), dataclasses.replace(config, static_ground_height_std_m=0.0))
    np.testing.assert_allclose(no_ground.bias_covariances[:, 1, 1], LATERAL_STD_M**2, rtol=0.05)
    along = np.sqrt(static.covariances[:, 0, 0] + static.bias_covariances[:, 0, 0]) / RANGES
    # near, the stance (0.14 m) dominates; beyond, the pixel noise's r sigma / h grows with range
    assert np.all(np.diff(along[1:]) > 0)
    assert along[-1] <= ground_module.STATIC_GROUND_MAX_RELATIVE_STD


@pytest.mark.parametrize("noise_px, limit, valid", [
    (1.0, 0.2, [True, True, True, True]),
    (3.0, 0.2, [True, True, True, True]),
    (1.0, 0.015, [True, True, True, False]),
    (3.0, 0.03, [True, True, True, False]),
    (3.0, 0.015, [True, True, False, False]),
    (3.0, 0.01, [True, False, False, False]),
])
def test_static_range_follows_the_foot_points_variance(noise_px, limit, valid, monkeypatch):
    # 6 m up: the pixel noise alone spreads the cut by about r^2 sigma / (f h), 1.6 % of 120 m at 1 px
    monkeypatch.setattr(ground_module, "STATIC_GROUND_MAX_RELATIVE_STD", limit)
    cue = run(static_frame("static"), FusedConfig(), noise_px)
    assert cue.valid.tolist() == valid
    assert all(r == "beyond-range" for r in cue.reason_names[~cue.valid])


def test_static_trust_order_puts_the_ground_first():
    assert TRUST_ORDER[0] == "height" and STATIC_TRUST_ORDER[0] == "ground"


def test_box_bottom_bounds_the_range():
    frame = static_frame("static")
    boxes = frame.detections.boxes
    bound = box_bottom_ranges(frame, boxes, frame.cam_to_world[:3, 3])
    # the keypoint box ends at the ankles (about 8 cm up): the bound lies a little beyond the person
    assert np.all(bound > RANGES) and np.all(bound < RANGES * 1.1)
    up = boxes.copy()
    up[:, 3] = -200.0  # bottoms above the horizon (0.4 deg above the top row at 20 deg down): no bound
    assert np.isinf(box_bottom_ranges(frame, up, frame.cam_to_world[:3, 3])).all()


def test_static_ground_variance_adds_the_calibrations_error():
    config = FusedConfig(static_ground_height_std_m=0.02, static_camera_tilt_std_deg=0.2,
                         static_camera_height_std_m=0.04, ankle_keypoint_offset_std_m=0.0)
    # 0.02^2 + 0.04^2 = 0.002 m^2, plus (0.2 deg in rad * r)^2: 0.0034907^2 * 100 = 0.0012185 at 10 m
    np.testing.assert_allclose(static_ground_variance(np.array([0.0, 10.0, 50.0]), config),
                               [0.002, 0.0032185, 0.0324617], rtol=1e-4)
    assert static_ground_variance(np.array([0.0, 50.0]), EXACT) == pytest.approx([0.02**2] * 2)


def test_tilt_widens_the_cut_by_r2_over_h():
    frame = static_frame("static")
    flat = run(frame, EXACT)
    tilted = run(frame, dataclasses.replace(EXACT, static_camera_tilt_std_deg=0.2))
    np.testing.assert_allclose(tilted.positions, flat.positions)  # the means do not move
    np.testing.assert_allclose(tilted.covariances, flat.covariances)  # nor the frame-to-frame part
    added = np.trace(tilted.bias_covariances - flat.bias_covariances, axis1=1, axis2=2)
    # a ground tilted by t at r metres is r t high there; the cut moves r / (h - ankle) times that
    r = np.linalg.norm(flat.positions, axis=1)
    expected = (np.radians(0.2) * r) ** 2 * (r / (6.0 - ankle_height(EXACT))) ** 2
    np.testing.assert_allclose(added, expected, rtol=1e-3)
    # 6 m up: 0.061 m at 10 m, 0.53 m at 30 m, 2.1 m at 60 m, 8.5 m at 120 m (7 % of the range)
    np.testing.assert_allclose(np.sqrt(added), [0.0613, 0.531, 2.12, 8.49], rtol=3e-3)


def test_camera_height_error_scales_the_range():
    frame = static_frame("static")
    flat = run(frame, EXACT)
    raised = run(frame, dataclasses.replace(EXACT, static_camera_height_std_m=0.04))
    added = np.trace(raised.bias_covariances - flat.bias_covariances, axis1=1, axis2=2)
    r = np.linalg.norm(flat.positions, axis=1)
    # a height error of 0.04 m moves the cut by 0.04 r / (h - ankle): 0.68 % of the range 6 m up
    np.testing.assert_allclose(np.sqrt(added) / r, 0.04 / (6.0 - ankle_height(EXACT)), rtol=1e-3)


@pytest.mark.parametrize("mount", ["static", "vehicle"])
def test_ankle_offset_spread_widens_only_the_static_ground(mount):
    frame = static_frame(mount, RANGES[:2]) if mount == "static" else static_frame(mount, np.array([8.0, 12.0]))
    flat = run(frame, EXACT)
    spread = run(frame, dataclasses.replace(EXACT, ankle_keypoint_offset_std_m=0.042))
    added = np.trace(spread.bias_covariances - flat.bias_covariances, axis1=1, axis2=2)
    np.testing.assert_allclose(spread.positions, flat.positions)
    if mount == "vehicle":  # the road's height under the person (ROAD_HEIGHT_STD_M) holds it there
        np.testing.assert_allclose(added, 0.0, atol=1e-12)
        return
    # a person's ankle keypoint 0.042 m off the offset moves the cut by 0.042 r / (h - ankle) along the ray
    r = np.linalg.norm(flat.positions, axis=1)
    np.testing.assert_allclose(np.sqrt(added) / r, 0.042 / (6.0 - ankle_height(EXACT)), rtol=1e-3)
    assert static_ground_variance(np.array([0.0]), FusedConfig())[0] == pytest.approx(0.02**2 + 0.04**2 + 0.042**2)


@pytest.mark.parametrize("mount", ["static", "vehicle"])
def test_ankle_offset_cuts_the_ray_with_a_higher_ground(mount):
    frame = static_frame(mount, RANGES[:1]) if mount == "static" else static_frame(mount, np.array([12.0]))
    exact = run(frame, EXACT)
    lifted = run(frame, dataclasses.replace(EXACT, ankle_keypoint_offset_m=0.039))
    assert ankle_height(EXACT) == pytest.approx(0.046 * 1.72)
    assert ankle_height(FusedConfig()) == pytest.approx(0.046 * 1.72 + 0.039)  # the real network's, on KITTI
    # exact skeletons have their ankles at the anatomical height: a plane 0.039 m higher meets the
    # ankle's ray nearer by the ratio of the camera's heights above the two planes
    ratio = np.linalg.norm(lifted.positions, axis=1) / np.linalg.norm(exact.positions, axis=1)
    h = 6.0 - ankle_height(EXACT)
    np.testing.assert_allclose(ratio, (h - 0.039) / h, rtol=1e-4)
    assert ratio[0] == pytest.approx(0.99341, abs=1e-4)  # 0.66 % nearer from 6 m up


@pytest.mark.parametrize("field, value", [
    ("static_camera_tilt_std_deg", -0.1), ("static_camera_tilt_std_deg", 10.5),
    ("static_camera_height_std_m", 5.5), ("ankle_keypoint_offset_m", 0.6), ("ankle_keypoint_offset_m", float("nan")),
    ("ankle_keypoint_offset_std_m", -0.01), ("ankle_keypoint_offset_std_m", 0.6),
])
def test_calibration_and_ankle_settings_are_checked(field, value):
    with pytest.raises(InputError, match=f"fused.{field} must be"):
        FusedConfig(**{field: value})
