"""Where the pose network runs: the providers asked for per device, the CPU fallback of ``auto``,
the one clear error of ``cuda`` without a GPU, and batched passes giving what single passes give."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.pose.providers import CPU, CUDA, TENSORRT, SessionConfig, wanted_providers


@pytest.mark.parametrize("device, available, wanted", [
    ("cpu", [TENSORRT, CUDA, CPU], [CPU]),
    ("auto", ["AzureExecutionProvider", CPU], [CPU]),
    ("auto", [CUDA, CPU], [CUDA, CPU]),
    ("cuda", [CUDA, CPU], [CUDA, CPU]),
    ("auto", [TENSORRT, CUDA, CPU], [TENSORRT, CUDA, CPU]),
    ("cuda", [CPU], "--device cuda: this onnxruntime has no CUDA provider .*gpu extra"),
    ("gpu", [CUDA, CPU], "device must be one of auto, cpu, cuda, got 'gpu'"),
])
def test_the_providers_asked_for_per_device(device, available, wanted, tmp_path):
    if isinstance(wanted, str):
        with pytest.raises(InputError, match=wanted):
            wanted_providers(device, available, tmp_path)
        return
    got = wanted_providers(device, available, tmp_path)
    assert [p if isinstance(p, str) else p[0] for p in got] == wanted
    if TENSORRT in wanted:  # TensorRT keeps its engines (one per input size) in the cache
        assert got[0][1] == {"trt_engine_cache_enable": True, "trt_engine_cache_path": str(tmp_path)}


@pytest.mark.parametrize("options, message", [
    ({"threads": 0}, r"threads must be an integer in \[1, 64\], got 0"),
    ({"device": None}, "device must be one of"),
    ({"batch": "yes"}, "batch must be true or false"),
    ({"spin_wait": 1}, "spin_wait must be true or false"),
    ({"side_by_side": "yes"}, "side_by_side must be true or false"),
    ({"gpu": 0}, "unknown onnx backend option.* gpu; valid: device, threads, spin_wait, batch"),
])
def test_session_options_are_checked(options, message):
    with pytest.raises(InputError, match=message):
        SessionConfig.of(None, options)


@pytest.mark.onnx_model
@pytest.mark.ultralytics
def test_auto_runs_on_the_cpu_here_and_cuda_is_one_clear_error(use_pose_cache):
    import onnxruntime as ort

    from pedenv.detection import create_detector

    if CUDA in ort.get_available_providers():
        pytest.skip("this onnxruntime has the CUDA provider: the CPU-only fallback is not what runs here")
    pose = create_detector("onnx", detection="fast", device="auto")
    assert pose.provider == CPU and pose.describe()["provider"] == CPU and not pose.network.batches
    assert create_detector("onnx", detection="fast", device="cpu").provider == CPU
    with pytest.raises(InputError, match="--device cuda: this onnxruntime has no CUDA provider"):
        create_detector("onnx", detection="fast", device="cuda")


@pytest.mark.onnx_model
@pytest.mark.ultralytics
def test_a_batch_of_passes_gives_what_the_passes_give_one_by_one(use_pose_cache, photo):
    from pedenv.images import read_image_rgb
    from pedenv.pose.onnx_backend import OnnxPose
    from pedenv.pose.postprocess import decode, letterbox, to_input_tensor

    image = read_image_rgb(photo("bus.jpg"))  # 810x1080, 4 people
    crops = [(0, 0, 810, 1080), (0, 300, 405, 1000), (400, 300, 810, 1000), (100, 400, 500, 800)]
    sizes = [(640, 480), (416, 256), (416, 256), (320, 320)]
    inputs = [letterbox(image[y0:y1, x0:x1], size) for (x0, y0, x1, y1), size in zip(crops, sizes)]
    tensors = [to_input_tensor(padded) for padded, _ in inputs]
    batched = OnnxPose(batch=True)
    assert batched.batches
    together = batched.infer_batch(tensors)
    assert batched.network_runs == 3  # the two 416x256 passes ran as one batch
    single = OnnxPose(batch=False)
    apart = single.infer_batch(tensors)
    assert single.network_runs == 4
    for a, b, (_, box) in zip(together, apart, inputs):
        assert a.shape == b.shape and a.shape[0] == 1
        np.testing.assert_allclose(a, b, rtol=1e-3, atol=1e-2)
        da, db = decode(a, box, 0.25, 0.7, 300), decode(b, box, 0.25, 0.7, 300)
        assert len(da) == len(db)
        np.testing.assert_allclose(da.boxes, db.boxes, atol=0.05)
    assert len(decode(together[0], inputs[0][1], 0.25, 0.7, 300)) >= 4


def test_a_gpu_input_is_padded_to_few_shapes():
    from pedenv.pose.onnx_backend import gpu_input_shape

    assert gpu_input_shape((1, 3, 384, 640)) == (1, 3, 384, 640)
    assert gpu_input_shape((3, 3, 192, 352)) == (4, 3, 256, 384)
    assert gpu_input_shape((5, 3, 672, 608), batch_dynamic=False) == (5, 3, 768, 640)
    widths = {gpu_input_shape((1, 3, 192, w))[3] for w in range(128, 640 + 1, 32)}
    assert widths == {128, 256, 384, 512, 640}


@pytest.mark.onnx_model
@pytest.mark.ultralytics
def test_a_padded_input_finds_the_same_persons_at_the_same_pixels(use_pose_cache, photo):
    from pedenv.images import read_image_rgb
    from pedenv.pose.onnx_backend import OnnxPose, gpu_input_shape, pad_input
    from pedenv.pose.postprocess import decode, letterbox, to_input_tensor

    image = read_image_rgb(photo("bus.jpg"))  # 810x1080, 4 people
    pose = OnnxPose(batch=False)
    for (x0, y0, x1, y1), size in [((0, 0, 810, 1080), (640, 480)), ((0, 300, 405, 1000), (416, 288))]:
        padded, box = letterbox(image[y0:y1, x0:x1], size)
        tensor = to_input_tensor(padded)
        grown = pad_input(np.concatenate([tensor, tensor]), gpu_input_shape((2, *tensor.shape[1:])))
        assert grown.shape[0] == 2 and grown.shape[2] % 128 == 0 and grown.shape[3] % 128 == 0
        plain, wide = (decode(pose.infer(t)[:1], box, 0.25, 0.7, 300) for t in (tensor, grown))
        assert len(plain) >= 1 and len(wide) == len(plain)
        order = [int(np.argmin(np.abs(wide.boxes[:, 0] - b[0]))) for b in plain.boxes]
        heights = (plain.boxes[:, 3] - plain.boxes[:, 1])[:, None]
        # the same boxes; a person cut by the image's right edge, where grey now follows, moves most (1 %)
        assert (np.abs(wide.boxes[order] - plain.boxes) / heights).max() < 0.02
    # on a GPU the first shapes run as they are, later new ones padded (the session table filled by hand here)
    from pedenv.pose.onnx_backend import GPU_EXACT_SESSIONS
    seen = [(1, 3, 192, 96 + 32 * k) for k in range(GPU_EXACT_SESSIONS)]
    pose._gpu_sessions = dict.fromkeys(seen)
    assert pose._gpu_input(np.zeros(seen[-1], np.float32)).shape == seen[-1]
    assert pose._gpu_input(np.zeros((3, 3, 192, 352), np.float32)).shape == (4, 3, 256, 384)


@pytest.mark.onnx_model
@pytest.mark.ultralytics
def test_passes_side_by_side_give_what_they_give_one_after_another(use_pose_cache, photo):
    from pedenv.images import read_image_rgb
    from pedenv.pose.onnx_backend import OnnxPose
    from pedenv.pose.postprocess import letterbox, to_input_tensor

    image = read_image_rgb(photo("bus.jpg"))
    crops = [(0, 0, 810, 1080), (0, 300, 405, 1000), (400, 300, 810, 1000), (100, 400, 500, 800), (0, 0, 405, 540)]
    sizes = [(640, 480), (416, 256), (416, 256), (320, 320), (256, 192)]
    tensors = [to_input_tensor(letterbox(image[y0:y1, x0:x1], size)[0])
               for (x0, y0, x1, y1), size in zip(crops, sizes)]
    pose = OnnxPose(threads=2)
    assert pose.side_by_side  # the CPU, two threads, no batching
    together = pose.infer_many(tensors)
    assert pose.network_runs == 5
    alone = OnnxPose(threads=2, side_by_side=False)
    assert not alone.side_by_side
    apart = [alone.infer(t) for t in tensors]
    for a, b in zip(together, apart, strict=True):  # in order; one thread sums some convolutions in another order
        assert a.shape == b.shape
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-3)
    assert not OnnxPose(threads=1).side_by_side  # one thread: nothing to split
    assert not OnnxPose(batch=True).side_by_side  # a batch instead


@pytest.mark.onnx_model
@pytest.mark.ultralytics
@pytest.mark.slow
def test_stream_finds_the_same_persons_with_its_passes_side_by_side(use_pose_cache):
    from pedenv.detection import create_detector
    from pedenv.images import read_image_rgb

    from shared_paths import REAL_SAMPLES

    frames = sorted((REAL_SAMPLES / "mot17" / "MOT17-04-FRCNN" / "img1").glob("*.jpg"))[:3]  # a crowd
    side = create_detector("onnx", detection="stream")
    alone = create_detector("onnx", detection="stream", side_by_side=False)
    assert side.network.side_by_side and not alone.network.side_by_side
    for i, path in enumerate(frames):  # the cold start's band tiles, then two packed inputs a frame
        image = read_image_rgb(path)
        got, want = side.detect_frame(image, None, 0.1 * i), alone.detect_frame(image, None, 0.1 * i)
        assert side.last_passes == alone.last_passes and len(side.last_passes) >= 3
        assert len(got) == len(want) >= 25
        for field in ("keypoints", "confidences", "boxes", "scores"):
            np.testing.assert_allclose(getattr(got, field), getattr(want, field), rtol=0, atol=1e-3)
    assert side.network.network_runs == alone.network.network_runs


@pytest.mark.onnx_model
@pytest.mark.ultralytics
@pytest.mark.slow
def test_far_with_a_calibration_runs_its_levels_in_one_call_and_finds_the_same_persons(use_pose_cache):
    from pedenv.detection import create_detector
    from pedenv.detection.geometry import CameraGeometry
    from pedenv.images import read_image_rgb
    from pedenv.records import Camera

    from shared_paths import REAL_SAMPLES

    image = read_image_rgb(next((REAL_SAMPLES / "nuscenes-0061").glob("*CAM_BACK__*.jpg")))  # 1600x900
    geometry = CameraGeometry.level(Camera.from_fov().intrinsics, 1.5)  # the bands from the calibration
    side, alone = create_detector("onnx", detection="far"), create_detector("onnx", detection="far", side_by_side=False)
    calls = []
    many = side.network.infer_many
    side.network.infer_many = lambda tensors: calls.append(len(tensors)) or many(tensors)  # type: ignore[method-assign]
    got, want = side.detect(image, geometry), alone.detect(image, geometry)
    assert [p.kind for p in side.last_passes][:3] == ["full", "band", "band"]
    assert side.last_passes == alone.last_passes
    assert calls[0] == 3  # the whole frame and both bands together; then the cascade's packed inputs
    assert len(got) == len(want) >= 3
    for field in ("keypoints", "confidences", "boxes", "scores"):
        np.testing.assert_allclose(getattr(got, field), getattr(want, field), rtol=0, atol=1e-3)


def test_the_cuda_provider_picks_cudnn_algorithms_as_configured(tmp_path):
    got = wanted_providers("cuda", [CUDA, CPU], tmp_path)
    assert got[0] == (CUDA, {"cudnn_conv_algo_search": "HEURISTIC"}) and got[1] == CPU
    got = wanted_providers("auto", [CUDA, CPU], tmp_path, "exhaustive")
    assert got[0] == (CUDA, {"cudnn_conv_algo_search": "EXHAUSTIVE"})
    with pytest.raises(InputError, match="cudnn_search must be one of heuristic, exhaustive, default, got 'fast'"):
        SessionConfig(cudnn_search="fast")
