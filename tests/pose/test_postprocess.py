"""Letterbox and decoding of the YOLO-pose output, with hand-checked numbers."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.pose.postprocess import (
    Letterbox,
    decode,
    frame_image,
    letterbox,
    parse_input_size,
    read_image_rgb,
    to_input_tensor,
    to_input_tensor_plain,
)
from pedenv.records import Camera, EgoPose, Frame


@pytest.mark.parametrize("size, expected", [
    (640, (640, 640)), ("640", (640, 640)), ("384x640", (384, 640)), ((384, 640), (384, 640)),
    ("384X640", (384, 640)), ("100", ValueError), ("0", ValueError), ("abc", ValueError),
    ("32x64x96", ValueError), (None, ValueError),
])
def test_parse_input_size(size, expected):
    if expected is ValueError:
        with pytest.raises(ValueError, match="input size"):
            parse_input_size(size)
    else:
        assert parse_input_size(size) == expected


@pytest.mark.parametrize("image_size, input_size, scale, pad_left, pad_top", [
    ((900, 1600), (384, 640), 0.4, 0, 12),          # 360x640 + 12 rows above, 12 below
    ((900, 1600), (640, 640), 0.4, 0, 140),         # 360x640 + 140 above, 140 below
    ((1080, 810), (640, 640), 640 / 1080, 80, 0),   # bus.jpg: 640x480, 80 columns each side
    ((720, 1280), (384, 640), 0.5, 0, 12),          # zidane.jpg
    ((101, 100), (64, 64), 64 / 101, 0, 0),         # 64x63: the odd column goes right
])
def test_letterbox_fit(image_size, input_size, scale, pad_left, pad_top):
    box = Letterbox.fit(image_size, input_size)
    assert box.scale == pytest.approx(scale)
    assert (box.pad_left, box.pad_top) == (pad_left, pad_top)


def test_letterbox_pads_with_114_and_maps_back():
    image = np.full((900, 1600, 3), 200, np.uint8)
    padded, box = letterbox(image, (384, 640))
    assert padded.shape == (384, 640, 3) and padded.dtype == np.uint8
    assert (padded[:12] == 114).all() and (padded[-12:] == 114).all()
    assert (padded[12:372] == 200).all()
    # input (0, 12) is the image's top-left corner, (640, 372) its bottom-right one
    np.testing.assert_allclose(box.to_image(np.array([[0.0, 12.0], [640.0, 372.0], [320.0, 192.0]])),
                               [[0.0, 0.0], [1600.0, 900.0], [800.0, 450.0]])
    # points in the padding are clipped to the image
    np.testing.assert_allclose(box.to_image(np.array([[-5.0, 0.0]])), [[0.0, 0.0]])


def test_to_input_tensor():
    padded = np.zeros((32, 64, 3), np.uint8)
    padded[..., 0] = 255
    padded[..., 2] = 114
    x = to_input_tensor(padded)
    assert x.shape == (1, 3, 32, 64) and x.dtype == np.float32
    assert x[0, 0].min() == 1.0 and x[0, 1].max() == 0.0
    assert x[0, 2, 0, 0] == pytest.approx(114 / 255)


@pytest.mark.parametrize("name, input_size", [
    ("nuscenes-0061/n015-2018-07-24-11-22-45+0800__CAM_BACK__1532402927637525.jpg", (384, 640)),  # 1600x900
    ("nuscenes-0061/n015-2018-07-24-11-22-45+0800__CAM_BACK__1532402927637525.jpg", (640, 640)),
    ("kitti/tracking_mini/training/image_02/0016/000002.png", (224, 640)),  # 1242x375
    ("kitti/tracking_mini/training/image_02/0016/000002.png", (384, 640)),
])
def test_to_input_tensor_equals_the_plain_conversion_on_a_real_image(name, input_size):
    from shared_paths import REAL_SAMPLES

    path = REAL_SAMPLES / name
    if not path.is_file():
        pytest.fail(f"{path}: the real samples are missing (see /work/shared/samples/real/README.md)")
    padded, _ = letterbox(read_image_rgb(path), input_size)
    fast, plain = to_input_tensor(padded), to_input_tensor_plain(padded)
    assert fast.shape == plain.shape == (1, 3, *input_size) and fast.dtype == plain.dtype == np.float32
    assert fast.flags.c_contiguous and np.array_equal(fast, plain)  # bit for bit, pad rows included


def _raw_output(persons: list[tuple[list[float], float, float]], anchors: int = 10) -> np.ndarray:
    """(1, 56, anchors) with given (box cx, cy, w, h), score and one keypoint offset per person."""
    out = np.zeros((1, 56, anchors), np.float32)
    for i, (box, score, dy) in enumerate(persons):
        out[0, :4, i] = box
        out[0, 4, i] = score
        kpts = np.zeros((17, 3))
        kpts[:, 0] = box[0]
        kpts[:, 1] = box[1] + dy + np.arange(17)
        kpts[:, 2] = 0.9
        out[0, 5:, i] = kpts.ravel()
    return out


def test_decode_hand_checked():
    box = Letterbox.fit((900, 1600), (384, 640))  # scale 0.4, 12 rows of padding on top
    out = _raw_output([([320, 192, 40, 80], 0.9, 0.0),     # centre of the image
                       ([322, 192, 40, 80], 0.8, 1.0),     # duplicate of the first: suppressed
                       ([100, 52, 20, 40], 0.5, 0.0),      # another person, top-left
                       ([500, 300, 20, 40], 0.25, 0.0)])   # at the threshold: dropped (score must be above)
    det = decode(out, box, score_threshold=0.25, iou_threshold=0.7)
    assert len(det) == 2
    np.testing.assert_allclose(det.scores, [0.9, 0.5], rtol=1e-6)
    np.testing.assert_allclose(det.boxes[0], [(300 - 0) / 0.4, (152 - 12) / 0.4, 340 / 0.4, (232 - 12) / 0.4])
    np.testing.assert_allclose(det.boxes[1], [90 / 0.4, (32 - 12) / 0.4, 110 / 0.4, (72 - 12) / 0.4])
    np.testing.assert_allclose(det.keypoints[0, :, 0], 800.0)
    np.testing.assert_allclose(det.keypoints[0, :, 1], (192 - 12 + np.arange(17)) / 0.4)
    np.testing.assert_allclose(det.confidences, 0.9, rtol=1e-6)


def test_decode_nothing_above_threshold():
    det = decode(_raw_output([([320, 192, 40, 80], 0.2, 0.0)]), Letterbox.fit((900, 1600), (384, 640)))
    assert len(det) == 0 and det.keypoints.shape == (0, 17, 2)


def _frame(**kw) -> Frame:
    return Frame(0, 0.0, Camera.from_fov(64, 48), EgoPose.from_xy_yaw(0, 0, 0), **kw)


def test_frame_image_reads_path_and_rejects_corrupt(tmp_path):
    import cv2

    good = tmp_path / "good.png"
    cv2.imwrite(str(good), np.dstack([np.full((4, 5), c, np.uint8) for c in (10, 20, 30)]))  # BGR
    image = frame_image(_frame(image_path=good))
    assert image.shape == (4, 5, 3) and tuple(image[0, 0]) == (30, 20, 10)  # RGB
    bad = tmp_path / "corrupt.jpg"
    bad.write_bytes(b"\xff\xd8 not really a jpeg")
    with pytest.raises(InputError, match="corrupt.jpg.*cannot read"):
        frame_image(_frame(image_path=bad))
    with pytest.raises(InputError, match="missing.png.*not found"):
        read_image_rgb(tmp_path / "missing.png")
    with pytest.raises(InputError, match="no image"):
        frame_image(_frame())
    with pytest.raises(InputError, match="uint8"):
        frame_image(_frame(image=np.zeros((4, 5, 3), np.float32)))
