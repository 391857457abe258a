"""``pedenv run`` on a vehicle's frames without --ego-poses: the poses estimated before the run and written."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
import yaml
from road_scene import CAMERA_HEIGHT_M, FOCAL, HEIGHT, WIDTH, cam_to_vehicle, render, texture, vehicle_pose

from pedenv.apps.options import OutputOptions, RecordingSource
from pedenv.apps.run import run_recording
from pedenv.errors import InputError
from pedenv.geometry import rotation_to_quaternion
from pedenv.odometry.recording import load_with_odometry
from pedenv.recordings.ego_poses import load_ego_poses
from pedenv.records import Detections, Frame


class NoPeople:
    """A pose backend that sees nobody (the run's other stages are not under test here)."""

    name = "no-people"

    def __call__(self, frame: Frame, tracks=None) -> Detections:  # noqa: ARG002 - the PoseBackend protocol
        return Detections.empty()


def _recording(folder, mounted: bool = True):
    mount = cam_to_vehicle(4.0)
    images = folder / "images"
    images.mkdir(parents=True)
    tex = texture()
    for i in range(4):
        cv2.imwrite(str(images / f"{i:06d}.png"), render(tex, vehicle_pose(0.9 * i, 0.0, 0.0), mount))
    calib = {"width": WIDTH, "height": HEIGHT, "fx": FOCAL, "fy": FOCAL, "cx": WIDTH / 2, "cy": HEIGHT / 2}
    if mounted:
        calib["cam_to_vehicle"] = {"rotation": rotation_to_quaternion(mount[:3, :3]).tolist(),
                                   "translation": [0.0, 0.0, CAMERA_HEIGHT_M]}
    (folder / "calib.yaml").write_text(yaml.safe_dump(calib))
    return images, folder / "calib.yaml"


def test_run_without_ego_poses_writes_the_estimated_ones(tmp_path):
    images, calib = _recording(tmp_path / "rec")
    out = tmp_path / "out"
    summary = run_recording(RecordingSource(images=images, calibration=calib, fps=10.0), OutputOptions(out),
                            backend=NoPeople())
    assert summary["frames_done"] == 4
    assert summary["ego_poses"]["source"] == "estimated" and summary["ego_poses"]["frames"] == 4
    assert summary["ego_poses"]["file"] == str(out / "ego_poses_estimated.csv")
    assert summary["ego_poses"]["keyframes"] == 4 and summary["ego_poses"]["frames_without_road_scale"] == []
    assert summary["ego_poses"]["frames_from_matched_descriptors"] == []
    poses = load_ego_poses(out / "ego_poses_estimated.csv")  # the --ego-poses format
    np.testing.assert_allclose(poses.timestamps, [0.0, 0.1, 0.2, 0.3])
    np.testing.assert_allclose(poses.translations[:, 0], [0.0, 0.9, 1.8, 2.7], atol=0.054)  # 2 % of the drive
    assert np.abs(poses.translations[:, 1:]).max() < 0.05


def test_given_ego_poses_win_and_nothing_is_estimated(tmp_path):
    images, calib = _recording(tmp_path / "rec")
    poses = tmp_path / "poses.csv"
    poses.write_text("timestamp,x,y,yaw\n0.0,0,0,0\n1.0,9,0,0\n")
    summary = run_recording(RecordingSource(images=images, calibration=calib, ego_poses=poses, fps=10.0),
                            OutputOptions(tmp_path / "out"), backend=NoPeople())
    assert not (tmp_path / "out" / "ego_poses_estimated.csv").exists()
    assert summary["ego_poses"] == {"source": "given", "file": str(poses)}


def test_a_calibration_without_the_mounting_is_refused_in_one_line(tmp_path):
    images, calib = _recording(tmp_path / "rec", mounted=False)
    with pytest.raises(InputError, match=r"calib\.yaml: estimating the ego motion from the images needs the "
                                         r"camera's mounting: add cam_to_vehicle"):
        load_with_odometry(calibration=calib, images=images, fps=10.0)


def test_a_static_mount_needs_no_odometry(tmp_path):
    images, calib = _recording(tmp_path / "rec")
    calib.write_text(calib.read_text() + "mount: static\n")
    recording = load_with_odometry(calibration=calib, images=images, fps=10.0)
    assert recording.camera.static and recording.trajectory is None


def test_a_video_gets_its_poses_too(tmp_path):
    images, calib = _recording(tmp_path / "rec")
    video = tmp_path / "drive.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (WIDTH, HEIGHT))
    for path in sorted(images.iterdir()):
        writer.write(cv2.imread(str(path)))
    writer.release()
    trajectory = load_with_odometry(calibration=calib, video=video).trajectory
    assert trajectory is not None
    np.testing.assert_allclose(trajectory.timestamps, [0.0, 0.1, 0.2, 0.3], atol=1e-6)
    np.testing.assert_allclose(trajectory.translations[:, 0], [0.0, 0.9, 1.8, 2.7], atol=0.054)


def test_calibrate_odometry_writes_the_same_poses_as_the_run(tmp_path):
    from pedenv.apps.odometry import estimate_ego_poses

    images, calib = _recording(tmp_path / "rec")
    summary = estimate_ego_poses(output=tmp_path / "vo", calibration=calib, images=images, fps=10.0,
                                 backend=NoPeople())
    assert summary["frames"] == 4 and abs(summary["distance_m"] - 2.7) < 0.054 and abs(summary["yaw_deg"]) < 0.1
    run_recording(RecordingSource(images=images, calibration=calib, fps=10.0), OutputOptions(tmp_path / "out"),
                  backend=NoPeople())
    assert (tmp_path / "vo" / "ego_poses_estimated.csv").read_bytes() == \
        (tmp_path / "out" / "ego_poses_estimated.csv").read_bytes()


def test_a_frame_too_dark_stops_the_run_with_the_frames_before_it_written(tmp_path):
    # frames 0-5 of the drive, then a black frame: frames 0 and 1 had their poses (each final 4 frames
    # later) and were run; the run stops with one line, their outputs and poses on disk
    images, calib = _recording(tmp_path / "rec")
    mount, tex = cam_to_vehicle(4.0), texture()
    for i in range(4, 6):
        cv2.imwrite(str(images / f"{i:06d}.png"), render(tex, vehicle_pose(0.9 * i, 0.0, 0.0), mount))
    cv2.imwrite(str(images / "000006.png"), np.zeros((HEIGHT, WIDTH, 3), np.uint8))
    out = tmp_path / "out"
    with pytest.raises(InputError, match=r"000005\.png: frame 5: too dark, blurred or covered for visual odometry"):
        run_recording(RecordingSource(images=images, calibration=calib, fps=10.0), OutputOptions(out),
                      backend=NoPeople())
    assert len((out / "environment.jsonl").read_text().splitlines()) == 2
    poses = load_ego_poses(out / "ego_poses_estimated.csv")
    np.testing.assert_allclose(poses.translations[:, 0], [0.0, 0.9], atol=0.054)
    summary = json.loads((out / "run.json").read_text())
    assert summary["frames_done"] == 2 and summary["ego_poses"]["frames"] == 2
