"""KITTI readers on the real samples (shared/samples/real/kitti) and on broken copies."""

import numpy as np
import pytest

from pedenv.datasets import kitti_files as kitti
from pedenv.errors import InputError

from shared_paths import REAL_SAMPLES

TRACKING = REAL_SAMPLES / "kitti" / "tracking_mini" / "training"
OBJECT = REAL_SAMPLES / "kitti" / "object_samples" / "training"


def test_calib_of_tracking_0016_has_its_recording_day_intrinsics():
    calib = kitti.read_calib(TRACKING / "calib" / "0016.txt")
    assert calib.K[0, 0] == pytest.approx(707.0493)
    assert calib.K[:2, 2] == pytest.approx([604.0814, 180.5066])
    assert calib.cam2_position[0] == pytest.approx(-0.06, abs=0.005)
    assert calib.R0_rect.shape == (3, 3) and calib.Tr_imu_to_velo.shape == (3, 4)


def test_calib_reads_the_original_tracking_spelling(tmp_path):
    text = (TRACKING / "calib" / "0001.txt").read_text()
    original = (text.replace("R0_rect:", "R_rect").replace("Tr_velo_to_cam:", "Tr_velo_cam")
                .replace("Tr_imu_to_velo:", "Tr_imu_velo"))
    path = tmp_path / "0001.txt"
    path.write_text(original)
    a, b = kitti.read_calib(path), kitti.read_calib(TRACKING / "calib" / "0001.txt")
    assert np.array_equal(a.R0_rect, b.R0_rect) and np.array_equal(a.Tr_velo_to_cam, b.Tr_velo_to_cam)
    assert a.K[0, 0] == pytest.approx(721.5377)


def test_tracking_labels_frame_12_of_0016():
    labels = kitti.read_labels(TRACKING / "label_02" / "0016.txt")
    frame = labels.in_frame(12)
    assert len(frame.of_type("Pedestrian")) == 8
    assert len(frame.of_type("DontCare")) == 4
    assert len(frame.of_type("Car")) == 4
    people = frame.of_type("Pedestrian")
    heights = people.boxes[:, 3] - people.boxes[:, 1]
    assert heights.min() >= 59 and heights.max() <= 143
    assert np.all((people.locations[:, 2] > 9) & (people.locations[:, 2] < 21))
    assert np.all(frame.of_type("DontCare").track_id == -1)
    # whole-sequence counts from the README
    assert len(labels.of_type("Pedestrian")) == 2027 and len(np.unique(labels.of_type("Pedestrian").track_id)) == 19


def test_projected_bottom_centre_lands_at_the_foot_of_the_2d_box():
    seq = kitti.read_tracking_sequence(TRACKING, "0016")
    people = seq.labels.in_frame(12).of_type("Pedestrian")
    uv = seq.calib.project(people.locations)
    centre_u = (people.boxes[:, 0] + people.boxes[:, 2]) / 2
    assert np.abs(uv[:, 0] - centre_u).max() < 25
    assert np.abs(uv[:, 1] - people.boxes[:, 3]).max() < 15


def test_the_labelled_ground_lies_under_kittis_camera_and_rendered_people_stand_on_it():
    from pedenv.calibration.observations import rendered_observations

    seq = kitti.read_tracking_sequence(TRACKING, "0016")
    height, tilt, roll = seq.labels.camera_over_ground()
    # the boxes' bottoms of the parked drive: KITTI's camera 1.65 m over the road, looking about level
    assert height == pytest.approx(1.63, abs=0.01) and abs(np.degrees(tilt)) < 1.0 and abs(np.degrees(roll)) < 2.5
    people = seq.labels.of_type("Pedestrian")
    obs, seen = rendered_observations(people, seq.calib.K, np.random.default_rng(0))
    assert seen.shape == (len(people),) and len(obs) == seen.sum() > 100
    assert np.all(people.occluded[seen] <= 1) and np.all(obs.heads[:, 1] < obs.feet[:, 1] - 24)
    # the feet land where the labelled boxes' bottom centres project, within the rendering's noise
    bottoms = seq.calib.project(people.locations[seen])
    assert np.median(np.abs(obs.feet - bottoms)[:, 1]) < 5.0


def test_object_labels_have_no_frame_or_track_columns():
    labels = kitti.read_labels(OBJECT / "label_2" / "000000.txt")
    assert list(labels.types) == ["Pedestrian"]
    assert labels.frame[0] == -1 and labels.track_id[0] == -1
    assert labels.locations[0] == pytest.approx([1.84, 1.47, 8.41])
    assert labels.boxes[0, 3] - labels.boxes[0, 1] == pytest.approx(164.92)


def test_tracking_sequence_with_poses():
    seq = kitti.read_tracking_sequence(TRACKING, "0016")
    assert seq.frames == (2, 7, 12) and seq.image_path(7).is_file()
    assert seq.poses.shape == (209, 4, 4) and np.allclose(seq.poses[0], np.eye(4))
    assert np.linalg.norm(seq.poses[:, :3, 3], axis=1).max() < 0.02  # the stationary sequence
    moving = kitti.read_tracking_sequence(TRACKING, "0001")
    assert len(moving.poses) == 447 and np.linalg.norm(moving.poses[-1, :3, 3]) > 200
    assert len(moving.labels.in_frame(15).of_type("Pedestrian")) == 0
    assert kitti.tracking_sequence_names(TRACKING) == ["0001", "0016"]


@pytest.mark.parametrize("line, message", [
    ("0 -1 Walker -1 -1 -10 1 2 3 4 -1 -1 -1 -1000 -1000 -1000 -10", "unknown object type 'Walker'"),
    ("0 -1 Car -1 -1 -10 1 2 3 4 -1 -1 -1 -1000 -1000", "17 fields"),
    ("0 -1 Car -1 -1 -10 1 2 x 4 -1 -1 -1 -1000 -1000 -1000 -10", "must be numbers"),
    ("1.5 -1 Car -1 -1 -10 1 2 3 4 -1 -1 -1 -1000 -1000 -1000 -10", "frame must be an integer"),
])
def test_bad_label_lines_name_file_and_line(tmp_path, line, message):
    path = tmp_path / "0000.txt"
    path.write_text("0 -1 DontCare -1 -1 -10 1 2 3 4 -1 -1 -1 -1000 -1000 -1000 -10\n" + line + "\n")
    with pytest.raises(InputError, match=message) as info:
        kitti.read_labels(path)
    assert f"{path}:2:" in str(info.value)


def test_bad_calib_and_pose_files(tmp_path):
    calib = tmp_path / "c.txt"
    calib.write_text("P0: 1 2 3\n")
    with pytest.raises(InputError, match=r"c.txt:1: P0 must have 12 numbers"):
        kitti.read_calib(calib)
    calib.write_text("P0: " + " ".join(["1"] * 12) + "\n")
    with pytest.raises(InputError, match="calibration lacks P1, P2"):
        kitti.read_calib(calib)
    poses = tmp_path / "CameraTrajectory.txt"
    poses.write_text("1 0 0 0 0 1 0 0 0 0 1 0\n2 0 0 0 0 1 0 0 0 0 1 0\n")
    with pytest.raises(InputError, match=r"CameraTrajectory.txt:2: the 3x3 part is not a rotation"):
        kitti.read_camera_trajectory(poses)
    with pytest.raises(InputError, match="file not found"):
        kitti.read_calib(tmp_path / "missing.txt")
