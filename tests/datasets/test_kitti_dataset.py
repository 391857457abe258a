"""The KITTI tracking adapter on the real samples: world frame, ego motion, ground truth."""

import numpy as np
import pytest

from pedenv.datasets import open_dataset
from pedenv.errors import InputError
from pedenv.geometry import invert_transform, project

from shared_paths import REAL_SAMPLES

ROOT = REAL_SAMPLES / "kitti"


def test_sequences_frames_and_timestamps():
    data = open_dataset("kitti", ROOT)
    assert data.scene_names() == ["0001", "0016"] and data.default_pose_backend == "onnx"
    frames = list(data.frames("0016"))
    assert [f.timestamp for f in frames] == pytest.approx([0.2, 0.7, 1.2])
    assert all(f.image_path.is_file() and (f.camera.width, f.camera.height) == (1224, 370) for f in frames)
    assert [len(f.ground_truth) for f in frames] == [8, 8, 8]


def test_ground_truth_feet_project_onto_the_box_bottoms():
    for frame in open_dataset("kitti", ROOT).frames("0016"):
        gt = frame.ground_truth
        uv, depth = project(gt.positions, frame.camera.intrinsics, invert_transform(frame.cam_to_world))
        assert np.all(depth > 9) and np.abs(uv[:, 1] - gt.boxes[:, 3]).max() < 10
        assert np.all(
            (gt.positions[:, 2] > -0.1) & (gt.positions[:, 2] < 0.7)
        )  # z up; their ground lies 0.2-0.56 m above the road plane
        assert np.all(gt.heights > 1.0) and np.all(gt.heights < 2.1)


def test_moving_sequence_drives_forward_along_x():
    frames = list(open_dataset("kitti", ROOT).frames("0001"))
    step = frames[1].ego.translation - frames[0].ego.translation
    assert 4.5 < step[0] < 7.0 and abs(step[1]) < 0.5  # about 11 m/s for 0.5 s, forward = +x
    cam_height = frames[0].cam_to_world[2, 3] - frames[0].ego.translation[2]
    assert cam_height == pytest.approx(1.65, abs=0.01)


def test_unknown_sequence_and_bad_root(tmp_path):
    with pytest.raises(InputError, match="no sequence '0099'"):
        list(open_dataset("kitti", ROOT).frames("0099"))
    with pytest.raises(InputError, match="no KITTI tracking folder"):
        open_dataset("kitti", tmp_path)
