"""The onnx backend on tiny hand-built ONNX graphs (the `onnx` package, ultralytics extra),
its option checks, the model cache and its errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.pose import create_pose_backend, models
from pedenv.records import Camera, EgoPose, Frame


def _constant_model(path: Path, output: np.ndarray, input_hw=(64, 64)) -> Path:
    """An ONNX graph images (1, 3, H, W) -> ``output`` + 0 * mean(images)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    nodes = [
        helper.make_node("ReduceMean", ["images"], ["m"], keepdims=0),
        helper.make_node("Mul", ["m", "zero"], ["z"]),
        helper.make_node("Add", ["const", "z"], ["output0"]),
    ]
    graph = helper.make_graph(
        nodes, "fake-pose",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, *input_hw])],
        [helper.make_tensor_value_info("output0", TensorProto.FLOAT, list(output.shape))],
        [numpy_helper.from_array(output.astype(np.float32), "const"),
         numpy_helper.from_array(np.zeros((), np.float32), "zero")])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = 8
    onnx.save(model, path)
    return path


def _one_person_output(anchors: int = 4) -> np.ndarray:
    out = np.zeros((1, 56, anchors), np.float32)
    out[0, :5, 0] = [32, 32, 16, 32, 0.9]  # box centre (32, 32), 16 x 32, score 0.9
    kpts = np.column_stack([np.full(17, 32.0), 16.0 + 2 * np.arange(17), np.full(17, 0.8)])
    out[0, 5:, 0] = kpts.ravel()
    return out


@pytest.mark.ultralytics
def test_onnx_backend_on_a_constant_model(tmp_path):
    path = _constant_model(tmp_path / "fake.onnx", _one_person_output())
    backend = create_pose_backend("onnx", model_path=path)  # the network alone: one pass
    assert backend.name == "onnx" and backend.input_size == (64, 64)
    # a 128x256 image is scaled by 0.25 into 32x64 with 16 rows of padding above
    det = backend.detect(np.zeros((128, 256, 3), np.uint8))
    assert len(det) == 1
    np.testing.assert_allclose(det.boxes[0], [(24 - 0) / 0.25, (16 - 16) / 0.25, 40 / 0.25, (48 - 16) / 0.25])
    np.testing.assert_allclose(det.keypoints[0, :, 0], 128.0)
    np.testing.assert_allclose(det.keypoints[0, :, 1], np.clip((2 * np.arange(17)) / 0.25, 0, 128))
    np.testing.assert_allclose(det.confidences, 0.8, rtol=1e-6)
    frame = Frame(
        0, 0.0, Camera.from_fov(256, 128), EgoPose.from_xy_yaw(0, 0, 0), image=np.zeros((128, 256, 3), np.uint8)
    )
    assert len(backend(frame)) == 1


@pytest.mark.ultralytics
@pytest.mark.parametrize("shape", [(1, 3, 10), (1, 57, 100), (1, 56)])
def test_wrong_output_shape_names_file_and_shape(tmp_path, shape):
    path = _constant_model(tmp_path / "wrong.onnx", np.zeros(shape, np.float32))
    with pytest.raises(InputError, match=r"wrong\.onnx.*\(1, 56, N\).*" + re_shape(shape)):
        create_detector("onnx", model_path=path)


def re_shape(shape) -> str:
    return r"\(" + r", ".join(str(s) for s in shape) + r"\)"


@pytest.mark.ultralytics
def test_input_size_must_match_a_fixed_model(tmp_path):
    path = _constant_model(tmp_path / "fake.onnx", _one_person_output())
    with pytest.raises(InputError, match=r"fake\.onnx.*64x64.*384x640"):
        create_detector("onnx", model_path=path, input_size="384x640")


def test_not_an_onnx_file(tmp_path):
    path = tmp_path / "junk.onnx"
    path.write_bytes(b"not a model")
    with pytest.raises(InputError, match="junk.onnx.*not a readable ONNX model"):
        create_detector("onnx", model_path=path)
    with pytest.raises(InputError, match="absent.onnx.*not found"):
        create_detector("onnx", model_path=tmp_path / "absent.onnx")


@pytest.mark.parametrize("option, value", [
    ("score_threshold", 1.5), ("score_threshold", -0.1), ("iou_threshold", "0.7"), ("threads", 0),
    ("threads", 65), ("max_detections", 0), ("input_size", "100x100"),
])
def test_options_are_range_checked(tmp_path, option, value):
    with pytest.raises(ValueError, match=option.split("_")[0]):
        create_detector("onnx", model_path=tmp_path / "never-read.onnx", **{option: value})


def test_missing_cached_model_names_prepare(tmp_path, monkeypatch):
    monkeypatch.setenv("PEDENV_CACHE", str(tmp_path / "empty"))
    with pytest.raises(InputError, match="384x640.*pedenv models prepare"):
        create_detector("onnx", input_size="384x640")


@pytest.mark.parametrize("env, expected", [
    ({"PEDENV_CACHE": "/c/pe", "XDG_CACHE_HOME": "/x"}, "/c/pe"),
    ({"XDG_CACHE_HOME": "/x"}, "/x/pedenv"),
    ({"HOME": "/h"}, "/h/.cache/pedenv"),
])
def test_cache_dir(monkeypatch, env, expected):
    for name in ("PEDENV_CACHE", "XDG_CACHE_HOME"):
        monkeypatch.delenv(name, raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    assert models.cache_dir() == Path(expected)


def test_cached_model_path_and_input_size_choice(tmp_path):
    path = models.cached_model_path("ab" * 32, "yolo11n-pose", "384x640", tmp_path)
    assert path == tmp_path / "models" / ("ab" * 8) / "yolo11n-pose_384x640.onnx"
    assert models.choose_input_size(1600, 900) == (384, 640)
    assert models.choose_input_size(1280, 960) == (640, 640)


def test_missing_weights_file(tmp_path):
    with pytest.raises(InputError, match="nope.pt.*not found"):
        models.find_weights(tmp_path / "nope.pt")
