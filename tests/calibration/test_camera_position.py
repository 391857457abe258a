"""``camera_position``: where a vehicle camera whose mounting is estimated sits in the vehicle frame of its
ego poses (a tape measure's figures), which people and road cannot show: read, checked, carried into the
estimated mounting, its files and the spread of the positions."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from pedenv.apps.options import RecordingSource
from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.spread import widen_state
from pedenv.errors import InputError
from pedenv.recordings.footage import load_calibration, load_camera_position
from pedenv.records import Detections, EgoPose
from pedenv.state import EnvironmentState, Pedestrians

from shared_paths import REAL_SAMPLES

SIZE = "width: 1242\nheight: 375\nintrinsics: [[721.5377, 0, 609.5593], [0, 721.5377, 172.854], [0, 0, 1]]\n"
SYNC = REAL_SAMPLES / "kitti" / "raw_2011_09_26_drive_0002" / "2011_09_26_drive_0002_sync"


def _estimate(position: tuple[float, float] = (0.0, 0.0)) -> CameraEstimate:
    cov = np.diag([0.0, 0.05, np.radians(0.3), np.radians(0.2)]) ** 2
    return CameraEstimate(721.5, 1.65, np.radians(1.0), 0.0, cov, (1242, 375), (609.6, 172.9), 10, 100, 3.0, True,
                          position=position)


def test_the_camera_position_is_read_and_checked(tmp_path) -> None:
    path = tmp_path / "k.yaml"
    path.write_text(SIZE)
    assert load_camera_position(path) == (0.0, 0.0)  # none given: the vehicle origin under the camera
    path.write_text(SIZE + "camera_position: [1.7, -0.06]\n")
    assert load_camera_position(path) == (1.7, -0.06)
    with pytest.raises(InputError, match=r"k\.yaml: calibration field 'camera_position' places a vehicle camera"):
        load_camera_position(path, static=True)
    for bad, message in (("[1.7]", "must be finite numbers of shape \\(2,\\)"), ("[150, 0]", "must be within 100 m"),
                         ("[nan, 0]", "must be finite numbers")):
        path.write_text(SIZE + f"camera_position: {bad}\n")
        with pytest.raises(InputError, match=f"k\\.yaml: calibration field 'camera_position' {message}"):
            load_camera_position(path)
    path.write_text(SIZE + "camera_position: [1.7, 0]\ncam_to_vehicle: {rotation: [0.5, -0.5, 0.5, -0.5], "
                           "translation: [1.7, 0, 1.5]}\n")
    with pytest.raises(InputError, match="'camera_position' and 'cam_to_vehicle' both place the camera"):
        load_calibration(path)


def test_the_estimated_mounting_sits_at_the_camera_position_and_its_spread_under_the_camera() -> None:
    est = _estimate((1.7, -0.06))
    mount = est.camera("vehicle").cam_to_vehicle
    assert mount[:3, 3] == pytest.approx([1.7, -0.06, 1.65])
    assert np.array_equal(mount[:3, :3], _estimate().camera("vehicle").cam_to_vehicle[:3, :3])
    assert est.camera("static").cam_to_vehicle[:2, 3] == pytest.approx([0.0, 0.0])
    assert est.summary()["camera_position"] == [1.7, -0.06] and "camera_position" not in _estimate().summary()

    def spread(estimate: CameraEstimate, x: float) -> np.ndarray:
        people = Pedestrians(np.array([1]), np.array([3]), np.array([[x, 2.0, 0.0]]), np.zeros((1, 3)),
                             np.zeros((1, 2, 2)), np.zeros((1, 17, 2)), np.zeros((1, 17)), np.zeros((1, 4)),
                             np.zeros((1, 17, 3)), np.array([x]), np.array(["ground"]))
        ego = EgoPose(np.array([5.0, 3.0, 0.0]), np.eye(3))
        people = dataclasses.replace(people, positions=people.positions + ego.translation)
        return widen_state(EnvironmentState(0, 0.0, ego, people), estimate, ego).pedestrians.covariances[0]

    # a person 20 m ahead of the vehicle origin is 18.3 m ahead of a camera 1.7 m forward of it
    assert spread(est, 20.0) == pytest.approx(spread(_estimate((0.0, -0.06)), 18.3), rel=1e-6)
    assert spread(est, 20.0)[0, 0] < 0.95 * spread(_estimate(), 20.0)[0, 0]


class _NoPeople:
    """A pose backend that finds nobody (the raw drive holds no pedestrians)."""

    name = "detector-model"

    def detect(self, _image: np.ndarray) -> Detections:
        return Detections.empty()


def test_calibrate_writes_the_mounting_at_the_camera_position(tmp_path) -> None:
    from pedenv.apps.calibrate import calibrate

    poses = tmp_path / "poses.csv"  # KITTI raw 0002 drives straight ahead at about 9 m/s
    poses.write_text("timestamp,x,y,yaw\n" + "".join(f"{100 + i / 10:.1f},{0.91 * i:.3f},0,0\n" for i in range(10)))
    intrinsics = tmp_path / "k.yaml"
    intrinsics.write_text(SIZE + "camera_position: [0.81, 0.32]\n")
    source = RecordingSource(images=SYNC / "image_02" / "data", calibration=intrinsics, ego_poses=poses,
                             static=False, fps=10.0)
    summary = calibrate(output=tmp_path / "out", source=source, backend=_NoPeople())
    assert summary["camera_position"] == [0.81, 0.32] and summary["height_m"] == pytest.approx(1.65, rel=0.05)
    with pytest.warns(UserWarning, match="estimated"):
        camera = load_calibration(tmp_path / "out" / "calibration.yaml")
    assert camera.cam_to_vehicle[:2, 3] == pytest.approx([0.81, 0.32])
    assert camera.cam_to_vehicle[2, 3] == pytest.approx(summary["height_m"], abs=1e-4)
