"""YOLO11n-pose on real photographs: person counts, plausible skeletons, onnx == ultralytics."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from pedenv.images import read_image_rgb
from pedenv.skeleton import ANKLE_KEYPOINTS, HEAD_KEYPOINTS

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model]

#: Photo -> persons a person detector must find there.
PHOTOS = {"bus.jpg": 4, "zidane.jpg": 2}


@pytest.fixture(scope="module")
def onnx_square(pose_cache):
    from pedenv.pose.models import find_onnx_model
    from pedenv.pose.onnx_backend import OnnxPose

    return OnnxPose(find_onnx_model(640, cache=pose_cache), input_size=640)  # one 640x640 pass


@pytest.mark.parametrize("name, persons", PHOTOS.items())
def test_person_count_and_plausible_skeletons(onnx_square, photo, name, persons):
    image = read_image_rgb(photo(name))
    det = onnx_square.detect(image)
    assert len(det) == persons
    assert np.all(det.scores > 0.25) and np.all(np.diff(det.scores) <= 0)
    for kp, conf, box in zip(det.keypoints, det.confidences, det.boxes):
        seen = conf > 0.5
        head = [k for k in HEAD_KEYPOINTS if seen[k]]
        feet = [k for k in ANKLE_KEYPOINTS if seen[k]]
        if head and feet:  # image v grows downwards: the head is above the ankles
            assert kp[head, 1].max() < kp[feet, 1].min()
        margin = 0.1 * (box[2:] - box[:2])
        assert np.all(kp[seen] >= box[:2] - margin) and np.all(kp[seen] <= box[2:] + margin)
    assert np.all(det.keypoints >= 0) and np.all(det.keypoints <= [image.shape[1], image.shape[0]])


@pytest.mark.parametrize("size", [(640, 640), (384, 640)])
@pytest.mark.parametrize("name", PHOTOS)
def test_onnx_agrees_with_ultralytics(pose_cache, photo, name, size):
    from pedenv.pose.models import find_onnx_model
    from pedenv.pose.onnx_backend import OnnxPose
    from pedenv.pose.ultralytics_backend import UltralyticsPose

    image = read_image_rgb(photo(name))
    ours = OnnxPose(find_onnx_model(size, cache=pose_cache), input_size=size).detect(image)  # one pass
    ref = UltralyticsPose(input_size=size).detect(image)
    assert len(ours) == len(ref) > 0
    cost = np.linalg.norm(ours.boxes[:, None] - ref.boxes[None], axis=2)
    rows, cols = linear_sum_assignment(cost)
    diff = np.linalg.norm(ours.keypoints[rows] - ref.keypoints[cols], axis=2)
    assert diff.mean() < 2.0
    np.testing.assert_allclose(ours.scores[rows], ref.scores[cols], atol=0.02)


def test_rect_model_is_found_by_input_size(use_pose_cache, photo):
    from pedenv.detection import create_detector

    backend = create_detector("onnx", input_size="384x640")
    assert backend.network.input_size == (384, 640) and backend.config is None  # one pass
    assert len(backend.detect(read_image_rgb(photo("zidane.jpg")))) == 2


def test_annotate_images_writes_json_and_pictures(onnx_square, photo, tmp_path):
    from pedenv.apps.detect import annotate_images

    photos = [photo(p) for p in PHOTOS]
    path = annotate_images(photos, tmp_path / "out", onnx_square)
    data = json.loads(path.read_text())["images"]
    assert [len(d["persons"]) for d in data] == list(PHOTOS.values())
    assert (data[0]["width"], data[0]["height"], data[0]["backend"]) == (810, 1080, "onnx")
    person = data[0]["persons"][0]
    assert len(person["keypoints"]) == 17 and person["keypoints"][0]["name"] == "nose"
    assert set(person["keypoints"][0]) == {"name", "u", "v", "confidence"} and len(person["box"]) == 4
    drawn = read_image_rgb(tmp_path / "out" / "bus_pose.png")
    assert drawn.shape == (1080, 810, 3)
    assert np.abs(drawn.astype(int) - read_image_rgb(photos[0]).astype(int)).sum() > 0


def test_benchmark_pose_rows(use_pose_cache):
    from pedenv.pose.timing import benchmark_pose

    rows = benchmark_pose(repeats=1)
    assert [(r["backend"], r["input_size"]) for r in rows] == [
        ("onnx", "640x640"), ("onnx", "384x640"), ("ultralytics", "640x640")]
    assert all(r["ms_per_frame"] > 0 and r["persons"] >= 3 for r in rows)
