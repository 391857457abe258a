"""The pixel geometry of benchmarks/static_feet.py (where a static camera's ground cue puts MOT17's
people, in pixels) and benchmarks/box_bottoms.py (the same against KITTI's 3D boxes): cuts of rays
with lifted planes, the implied ankle height, a foot ahead, a perturbed calibration. Exact camera
models, no estimates."""

import sys

import numpy as np
import pytest

from pedenv.synthetic.scenarios import static_camera

from shared_paths import REAL_SAMPLES, REPO

sys.path.insert(0, str(REPO / "benchmarks"))

#: Ground points, vehicle frame, metres.
GROUND = np.array([[6.0, 2.0, 0.0], [9.0, -1.5, 0.0], [15.0, 0.5, 0.0]])


def cameras():
    """A synthetic static camera 6 m up looking 20 deg down, and MOT17-04's estimated one (7.29 m, 62 deg)."""
    from pedenv.datasets.ucmctrack import read_camera_parameters
    from pedenv.datasets.ucmctrack import static_camera as ucmc_camera

    out = [static_camera(6.0, 20.0)]
    path = REAL_SAMPLES / "mot17" / "ucmctrack_cam_para" / "MOT17-04-FRCNN.txt"
    if path.exists():
        out.append(ucmc_camera(read_camera_parameters(path), 1920, 1080))
    return out


@pytest.mark.parametrize("camera", cameras())
def test_an_ankle_straight_above_its_ground_point_has_no_error(camera):
    from static_feet import ankle_row, height_at_range, lifted_range, perturbed, project

    for point in GROUND:
        r = float(np.hypot(*(point[:2] - camera.cam_to_vehicle[:2, 3])))
        ankle, bottom = project(camera, point + [0.0, 0.0, 0.118]), project(camera, point)
        assert lifted_range(camera, bottom, 0.0) == pytest.approx(r, abs=1e-9)
        assert height_at_range(camera, ankle, r) == pytest.approx(0.118, abs=1e-9)
        cams = (camera, perturbed(camera, pitch_deg=0.5), perturbed(camera, lift_m=0.1))
        a, a_net, e, e_pitch, e_height = ankle_row(cams, ankle, bottom, r, r, 0.118)
        assert (a, a_net) == pytest.approx((0.118, 0.118), abs=1e-9)
        assert e == pytest.approx(0.0, abs=1e-9)
        # a wrong calibration moves truth and cue alike: centimetres, not the decimetres seen on MOT17-02
        assert abs(e_pitch) < 0.02 and abs(e_height) < 0.02


def test_a_higher_camera_scales_every_ground_range():
    from static_feet import lifted_range, perturbed, project

    camera = static_camera(6.0, 20.0)
    higher = perturbed(camera, lift_m=0.5)
    for point in GROUND:
        pixel = project(camera, point)
        assert lifted_range(higher, pixel, 0.0) == pytest.approx(lifted_range(camera, pixel, 0.0) * 6.5 / 6.0)


def test_a_foot_ahead_moves_the_bottom_by_the_level_cameras_formula():
    from static_feet import foot_pixels

    camera = static_camera(1.73, 0.0)  # level, as MOT17-02's camera nearly is
    f = float(camera.intrinsics[1, 1])
    for r in (7.0, 8.5, 22.0):
        point = np.array([r, 0.0, 0.0])
        expected = f * 1.73 * (1.0 / (r - 0.13) - 1.0 / r)  # the ground point 0.13 m nearer
        assert foot_pixels(camera, point, 0.13) == pytest.approx(expected, rel=1e-9)


def test_errors_split_along_and_across_the_ray():
    from static_feet import along_across

    camera = static_camera(6.0, 20.0)
    cov = np.diag([0.04, 0.01])
    along, across, sigma = along_across(camera, np.array([10.3, 0.2]), np.array([10.0, 0.0]), cov)
    assert (along, across, sigma) == pytest.approx((0.3, 0.2, 0.2))


def test_a_pixel_cut_with_a_plane_below_the_camera_gives_its_depth():
    from box_bottoms import cut_depth

    K = np.array([[720.0, 0.0, 610.0], [0.0, 720.0, 185.0], [0.0, 0.0, 1.0]])  # KITTI-like
    for point in ([1.0, 1.65, 9.0], [-3.0, 1.5, 20.0]):
        x = K @ np.array(point)
        assert cut_depth(K, x[:2] / x[2], point[1]) == pytest.approx(point[2])
    assert cut_depth(K, np.array([610.0, 100.0]), 1.65) == float("inf")  # above the horizon
