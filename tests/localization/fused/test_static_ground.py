"""The ground cue of a static camera: no 20 m limit, no road-height terms, its range from the foot point's variance."""

import dataclasses

import numpy as np
import pytest

from pedenv.config import FusedConfig
from pedenv.geometry import invert_transform, project
from pedenv.localization.fused.fusion import STATIC_TRUST_ORDER, TRUST_ORDER
from pedenv.localization.fused.ground import box_bottom_ranges, ground_cue
from pedenv.records import Camera, Detections, EgoPose, Frame
from pedenv.synthetic.scenarios import static_camera

from fused_frames import skeletons_of, upright_skeletons

#: People straight ahead of a camera 6 m up, 20 deg down, at these ranges (metres).
RANGES = np.array([10.0, 30.0, 60.0, 120.0])


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
    vehicle = run(static_frame("vehicle"))
    assert vehicle.valid.tolist() == [True, False, False, False]
    assert list(vehicle.reason_names[1:]) == ["beyond-range"] * 3
    static = run(static_frame("static"))
    assert static.valid.all()
    truth = np.column_stack([RANGES, np.linspace(-2.0, 2.0, len(RANGES))])
    rel = np.linalg.norm(static.positions - truth, axis=1) / RANGES
    assert rel.max() < 0.01  # exact skeletons: the cut with the calibrated ground is right


def test_static_variance_is_the_foot_points_alone():
    config = FusedConfig()
    static, vehicle = run(static_frame("static")), run(static_frame("vehicle"))
    # the per-person part along the ray holds the ground's unevenness only, not the road's height and curvature
    assert static.bias_covariances[0, 0, 0] < vehicle.bias_covariances[0, 0, 0]
    no_ground = run(static_frame("static"), dataclasses.replace(config, static_ground_height_std_m=0.0))
    np.testing.assert_allclose(no_ground.bias_covariances[:, 1, 1], config.lateral_std_m**2, rtol=0.05)
    along = np.sqrt(static.covariances[:, 0, 0] + static.bias_covariances[:, 0, 0]) / RANGES
    # near, the stance (0.14 m) dominates; beyond, the pixel noise's r sigma / h grows with range
    assert np.all(np.diff(along[1:]) > 0)
    assert along[-1] <= config.static_ground_max_relative_std


@pytest.mark.parametrize("noise_px, limit, valid", [
    (1.0, 0.2, [True, True, True, True]),
    (3.0, 0.2, [True, True, True, True]),
    (1.0, 0.015, [True, True, True, False]),
    (3.0, 0.03, [True, True, True, False]),
    (3.0, 0.015, [True, True, False, False]),
    (3.0, 0.01, [True, False, False, False]),
])
def test_static_range_follows_the_foot_points_variance(noise_px, limit, valid):
    # 6 m up: the pixel noise alone spreads the cut by about r^2 sigma / (f h), 1.6 % of 120 m at 1 px
    cue = run(static_frame("static"), FusedConfig(static_ground_max_relative_std=limit), noise_px)
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
