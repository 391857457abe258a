import numpy as np
import pytest

from pedenv.geometry import (
    closest_points,
    inverse_2x2,
    inverse_2x2_entries,
    invert_transform,
    pixel_rays,
    project,
    quaternion_to_rotation,
    rotation_from_ypr,
    rotation_to_quaternion,
    rotation_z,
)
from pedenv.records import EgoPose, Frame


def test_closest_points_of_skew_rays_hand_checked():
    # ray 1 along x; ray 2 from (0, 2, 1) heading (1, -1, 0)/sqrt2: closest at x = 2, one metre apart in z
    d2 = np.array([1.0, -1.0, 0.0]) / np.sqrt(2)
    s, t, mid, parallel = closest_points(np.zeros(3), np.array([1.0, 0, 0]), np.array([0.0, 2, 1]), d2)
    assert s == pytest.approx(2.0) and t == pytest.approx(2 * np.sqrt(2))
    np.testing.assert_allclose(mid, [2.0, 0.0, 0.5], atol=1e-12)
    assert not parallel


def test_parallel_rays_are_flagged_not_nan_propagating():
    d = np.array([[1.0, 0, 0], [0.6, 0.8, 0]])
    s, t, mid, parallel = closest_points(np.zeros((2, 3)), d, np.array([[0, 1.0, 0], [1, 0, 0]]), d)
    assert parallel.tolist() == [True, True]
    assert np.isnan(s).all()


def test_rays_and_projection_are_inverse(camera):
    frame = Frame(0, 0.0, camera, EgoPose.from_xy_yaw(3.0, -2.0, 0.4))
    pts = np.array([[20.0, 5.0, 0.0], [40.0, 10.0, 1.7], [10.0, 2.0, 1.0]])
    uv, depth = project(pts, camera.intrinsics, invert_transform(frame.cam_to_world))
    assert (depth > 0).all()
    rays = pixel_rays(uv, camera.intrinsics, frame.cam_to_world)
    want = pts - frame.cam_to_world[:3, 3]
    np.testing.assert_allclose(rays, want / np.linalg.norm(want, axis=1, keepdims=True), atol=1e-12)


def test_forward_camera_sees_straight_ahead_at_principal_point(camera):
    frame = Frame(0, 0.0, camera, EgoPose.from_xy_yaw(0, 0, 0))
    uv, depth = project(np.array([[30.0, 0.0, 1.5]]), camera.intrinsics, invert_transform(frame.cam_to_world))
    np.testing.assert_allclose(uv[0], [800, 450])
    assert depth[0] == pytest.approx(30.0)
    # a point to the left (y > 0) appears left of the centre (u < 800)
    uv, _ = project(np.array([[30.0, 3.0, 1.5]]), camera.intrinsics, invert_transform(frame.cam_to_world))
    assert uv[0, 0] < 800


def test_quaternion_round_trip_and_nuscenes_front_camera():
    r = rotation_from_ypr(0.3, -0.05, 0.02)
    np.testing.assert_allclose(quaternion_to_rotation(rotation_to_quaternion(r)), r, atol=1e-12)
    # FORMATS.md: a front camera looking straight ahead has rotation [0.5, -0.5, 0.5, -0.5]
    from pedenv.records import OPTICAL_TO_VEHICLE
    np.testing.assert_allclose(quaternion_to_rotation([0.5, -0.5, 0.5, -0.5]), OPTICAL_TO_VEHICLE, atol=1e-12)


def test_inverse_2x2_hand_checked_and_batched():
    # [[4, 7], [2, 6]]: determinant 10, inverse [[0.6, -0.7], [-0.2, 0.4]]
    np.testing.assert_allclose(inverse_2x2(np.array([[4.0, 7.0], [2.0, 6.0]])), [[0.6, -0.7], [-0.2, 0.4]], atol=1e-15)
    m = np.random.default_rng(3).normal(size=(5, 3, 2, 2)) + 3 * np.eye(2)
    np.testing.assert_allclose(inverse_2x2(m) @ m, np.broadcast_to(np.eye(2), m.shape), atol=1e-12)
    # the symmetric case on separate component arrays: [[2, 1], [1, 3]] -> [[3, -1], [-1, 2]] / 5
    a, b, c, d = inverse_2x2_entries(np.array([2.0]), np.array([1.0]), np.array([1.0]), np.array([3.0]))
    np.testing.assert_allclose(np.concatenate([a, b, c, d]), [0.6, -0.2, -0.2, 0.4], atol=1e-15)


def _rz_ry_rx(yaw, pitch, roll):
    cy, sy, cp, sp, cr, sr = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch), np.cos(roll), np.sin(roll)
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    return rz @ ry @ rx


def _textbook_quaternion_matrix(q):
    w, x, y, z = np.asarray(q, float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@pytest.mark.parametrize("ypr", [(0.0, 0.0, 0.0), (0.3, -0.05, 0.02), (-2.9, 0.4, -1.2), (np.pi, 1.5, 3.0)])
def test_rotations_agree_with_the_written_out_formulas(ypr):
    np.testing.assert_allclose(rotation_from_ypr(*ypr), _rz_ry_rx(*ypr), atol=1e-15)
    np.testing.assert_allclose(rotation_z(ypr[0]), _rz_ry_rx(ypr[0], 0.0, 0.0), atol=1e-15)
    q = rotation_to_quaternion(rotation_from_ypr(*ypr))
    assert q[0] >= 0 and np.linalg.norm(q) == pytest.approx(1.0)
    np.testing.assert_allclose(_textbook_quaternion_matrix(q), rotation_from_ypr(*ypr), atol=1e-15)
    np.testing.assert_allclose(quaternion_to_rotation(2.5 * q), _textbook_quaternion_matrix(q), atol=1e-15)


def test_half_turn_quaternion_hand_checked():
    # 180 degrees about z: q = [0, 0, 0, +-1]; a quarter turn about z: [cos 45, 0, 0, sin 45]
    np.testing.assert_allclose(np.abs(rotation_to_quaternion(np.diag([-1.0, -1.0, 1.0]))), [0, 0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(rotation_to_quaternion(rotation_z(np.pi / 2)), [np.sqrt(0.5), 0, 0, np.sqrt(0.5)],
                               atol=1e-15)


def test_pixel_rays_do_not_overflow_for_huge_pixels(camera):
    """Issue 10.2: 1e155 px and more overflowed the norm into NaN; normalising first keeps unit rays."""
    from pedenv.geometry import pixel_rays, unit_vectors

    pixels = np.array([[1e155, 1e155], [1e300, -1e300], [800.0, 450.0]])
    rays = pixel_rays(pixels, camera.intrinsics, np.eye(4))
    assert np.isfinite(rays).all()
    np.testing.assert_allclose(np.linalg.norm(rays, axis=1), 1.0)
    np.testing.assert_allclose(rays[0], [np.sqrt(0.5), np.sqrt(0.5), 0.0], atol=1e-12)
    assert unit_vectors(np.zeros((1, 3))).tolist() == [[0.0, 0.0, 0.0]]
