"""The estimate's uncertainty carried into ground positions."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.spread import calibration_covariances


def _estimate(height_std: float, tilt_std_deg: float) -> CameraEstimate:
    cov = np.diag([0.0, height_std ** 2, np.radians(tilt_std_deg) ** 2, 0.0])
    return CameraEstimate(1266.4, 6.0, np.radians(20.0), 0.0, cov, (1600, 900), (800.0, 450.0), 10, 100, 3.0)


def test_a_height_error_scales_every_range_and_a_tilt_error_grows_with_it() -> None:
    points = np.array([[10.0, 0.0, 0.0], [40.0, 0.0, 0.0]])
    height = calibration_covariances(points, _estimate(0.06, 0.0))  # 1 % of the height
    assert np.sqrt(height[:, 0, 0]) == pytest.approx([0.1, 0.4], rel=0.02)  # 1 % of each range
    tilt = calibration_covariances(points, _estimate(0.0, 0.5))
    # range error of a tilt error: r^2 / h (1 + h^2 / r^2) times it (radians)
    expected = [r * r / 6.0 * (1 + 36.0 / r ** 2) * np.radians(0.5) for r in (10.0, 40.0)]
    assert np.sqrt(tilt[:, 0, 0]) == pytest.approx(expected, rel=0.02)
    assert np.all(calibration_covariances(points, _estimate(0.0, 0.0)) == 0.0)


def test_a_vehicle_frame_turned_by_its_ego_pose_turns_the_spread() -> None:
    from pedenv.calibration.spread import widen_state
    from pedenv.records import EgoPose
    from pedenv.state import EnvironmentState, Pedestrians

    est = _estimate(0.06, 0.0)
    people = Pedestrians(np.array([1]), np.array([3]), np.array([[0.0, 20.0, 0.0]]), np.zeros((1, 3)),
                         np.zeros((1, 2, 2)), np.zeros((1, 17, 2)), np.zeros((1, 17)), np.zeros((1, 4)),
                         np.zeros((1, 17, 3)), np.array([20.0]), np.array(["ground"]))
    turned = EgoPose(np.zeros(3), np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))  # 90 deg left
    state = EnvironmentState(0, 0.0, turned, people)
    cov = widen_state(state, est, turned).pedestrians.covariances[0]
    assert np.sqrt(cov[1, 1]) == pytest.approx(0.2, rel=0.02)  # 20 m along the vehicle's x, now the world's y
    assert cov[0, 0] == pytest.approx(0.0, abs=1e-6)


def test_the_spread_matches_cameras_drawn_from_the_estimates_covariance() -> None:
    from pedenv.calibration.geometry import camera_rotation, ground_points, intrinsics, project

    cov = np.diag([12.0, 0.16, np.radians(0.15), np.radians(0.2)]) ** 2
    cov[0, 1] = cov[1, 0] = 0.6 * 12.0 * 0.16  # a longer focal length goes with a higher camera
    est = CameraEstimate(1266.4, 6.0, np.radians(20.0), np.radians(0.5), cov, (1600, 900), (800.0, 450.0), 10, 100,
                         3.0)
    points = np.array([[8.0, 3.0, 0.0], [25.0, -6.0, 0.0], [50.0, 10.0, 0.0]])
    pixels = project(points, intrinsics(est.focal, est.centre), camera_rotation(est.tilt, est.roll), est.height)
    draws = np.random.default_rng(0).multivariate_normal([est.focal, est.height, est.tilt, est.roll], cov, 4000)
    cuts = np.array([ground_points(pixels, intrinsics(f, est.centre), camera_rotation(t, r), h)[:, :2]
                     for f, h, t, r in draws])
    for i, spread in enumerate(calibration_covariances(points, est)):
        drawn = np.cov(cuts[:, i].T)
        assert np.sqrt(np.diag(spread)) == pytest.approx(np.sqrt(np.diag(drawn)), rel=0.05)
        assert spread[0, 1] / np.sqrt(spread[0, 0] * spread[1, 1]) == pytest.approx(
            drawn[0, 1] / np.sqrt(drawn[0, 0] * drawn[1, 1]), abs=0.03)
