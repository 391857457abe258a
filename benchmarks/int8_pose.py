"""INT8 YOLO11n-pose on the CPU: is a static-quantized model faster, and does it keep recall?

Exploratory (docs/speed.md, "INT8 on the CPU: measured, not shipped"): nothing here is wired into
pedenv's backends. Steps:

1. Quantize pedenv's prepared fp32 ONNX model (``find_onnx_model``: the cached dynamic export)
   with ``onnxruntime.quantization.quantize_static`` (QDQ, per-channel weights, U8 activations /
   S8 weights), calibrated on frames of Debian's street video
   ``/usr/share/doc/opencv-doc/examples/data/vtest.avi`` (opencv-doc), letterboxed as pedenv does
   (whole frames at 384x640 and 640x640 and 2x crops like far's tiles). Never on the test
   samples. Two variants: ``int8`` (every layer but the output decode) and ``int8-heads-fp32``
   (also the heads' last 1x1 convs, which write box, score and keypoint values, stay fp32).
2. Times one pass fp32 against each int8 model at 384x640 and 640x640, alternated in one
   process, 2 threads (pedenv's session options), median of ``--runs`` runs; prints ``uptime``.
3. Recall/precision on ``../shared/samples/real`` with ``evaluate_detections`` (``fast`` and
   ``far``) for each model, and the keypoint difference to fp32: persons matched by box IoU >= 0.5
   between fp32's and int8's ``far`` detections on the same image, mean and 95th percentile pixel
   distance of keypoints both models see (visibility > 0.5), in image px and in % of box height.

    PYTHONPATH=src python benchmarks/int8_pose.py [--out DIR] [--runs 40] [--skip-eval]
        [--variants int8,int8-heads-fp32,int8-ends-fp32] [--calibrate minmax|percentile]
        [--modes fast,far] [--no-keypoints]

The int8 models are written to ``--out`` (default: a temporary folder), never into the repository.
"""

from __future__ import annotations

import argparse
import subprocess
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from pedenv.pose.models import find_onnx_model
from pedenv.pose.postprocess import letterbox, to_input_tensor

VIDEO = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
SAMPLES = Path(__file__).resolve().parents[1] / ".." / "shared" / "samples" / "real"
SIZES = ((384, 640), (640, 640))


def video_frames(count: int) -> list[np.ndarray]:
    """``count`` frames spread over the street video, (H, W, 3) uint8 RGB."""
    cap = cv2.VideoCapture(str(VIDEO))
    total = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
    frames = []
    for index in np.linspace(0, total - 1, count).astype(int):
        cap.set(cv2.CAP_PROP_POS_FRAMES, int(index))
        ok, bgr = cap.read()
        if ok:
            frames.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
    cap.release()
    return frames


def calibration_inputs(count: int, seed: int = 0) -> list[np.ndarray]:
    """Network inputs (1, 3, h, w) float32 as pedenv feeds them: per frame one whole-frame letterbox
    (alternating 384x640 and 640x640) and one 2x crop (a far tile) letterboxed into 384x640."""
    rng = np.random.default_rng(seed)
    inputs = []
    for i, frame in enumerate(video_frames(count)):
        inputs.append(to_input_tensor(letterbox(frame, SIZES[i % 2])[0]))
        h, w = frame.shape[:2]
        ch, cw = h // 2, int(h // 2 * 640 / 384)
        top, left = rng.integers(0, h - ch + 1), rng.integers(0, w - cw + 1)
        inputs.append(to_input_tensor(letterbox(frame[top:top + ch, left:left + cw], SIZES[0])[0]))
    return inputs


#: The variants: name -> (heads' last convs in fp32, the first conv (on the raw image) in fp32).
VARIANTS = {"int8": (False, False), "int8-heads-fp32": (True, False), "int8-ends-fp32": (True, True)}


def excluded_nodes(model_path: Path, heads_fp32: bool, first_fp32: bool = False) -> list[str]:
    """Nodes left in fp32: the head's decode (``/model.23/`` outside its conv branches: DFL,
    anchors, concat of boxes, scores and keypoints); with ``heads_fp32`` the branches' last
    1x1 convs (``cv2.k.2``, ``cv3.k.2``, ``cv4.k.2``); with ``first_fp32`` the first conv block."""
    import onnx

    names = []
    for node in onnx.load(str(model_path)).graph.node:
        if first_fp32 and node.name.startswith("/model.0/"):
            names.append(node.name)
        if not node.name.startswith("/model.23/"):
            continue
        branch = any(f"/{b}." in node.name for b in ("cv2", "cv3", "cv4"))
        last_conv = branch and any(f"/{b}.{k}.2/" in node.name for b in ("cv2", "cv3", "cv4") for k in range(3))
        if not branch or (heads_fp32 and last_conv):
            names.append(node.name)
    return names


def quantize(model: Path, out: Path, inputs: list[np.ndarray], variant: str, method: str) -> Path:
    """Static QDQ quantization of ``model`` to ``out`` (per-channel S8 weights, U8 activations);
    ``variant`` a key of :data:`VARIANTS`, ``method`` the calibration (``minmax``, ``percentile``)."""
    from onnxruntime.quantization import (
        CalibrationDataReader,
        CalibrationMethod,
        QuantFormat,
        QuantType,
        quantize_static,
    )

    class Reader(CalibrationDataReader):
        def __init__(self) -> None:
            self.items = iter([{"images": x} for x in inputs])

        def get_next(self) -> dict | None:
            return next(self.items, None)

    quantize_static(str(model), str(out), Reader(), quant_format=QuantFormat.QDQ, per_channel=True,
                    activation_type=QuantType.QUInt8, weight_type=QuantType.QInt8,
                    nodes_to_exclude=excluded_nodes(model, *VARIANTS[variant]),
                    calibrate_method={"minmax": CalibrationMethod.MinMax,
                                      "percentile": CalibrationMethod.Percentile}[method])
    return out


def session(path: Path):  # onnxruntime has no stubs
    from pedenv.pose.providers import SessionConfig, create_session

    return create_session(path, SessionConfig(device="cpu", threads=2))[0]


def time_passes(models: dict[str, Path], runs: int) -> dict[str, dict[str, float]]:
    """Median ms of one pass per model and input size, the models alternated run by run."""
    sessions = {name: session(path) for name, path in models.items()}
    frame = video_frames(1)[0]
    medians: dict[str, dict[str, float]] = {name: {} for name in models}
    for size in SIZES:
        x = to_input_tensor(letterbox(frame, size)[0])
        times: dict[str, list[float]] = {name: [] for name in models}
        for sess in sessions.values():
            sess.run(None, {"images": x})  # warm-up
        for _ in range(runs):
            for name, sess in sessions.items():
                start = time.perf_counter()
                sess.run(None, {"images": x})
                times[name].append(1e3 * (time.perf_counter() - start))
        for name in models:
            medians[name][f"{size[0]}x{size[1]}"] = float(np.median(times[name]))
    return medians


def recall_rows(models: dict[str, Path], modes: tuple[str, ...], int8_score: float = 0.25) -> None:
    """Prints recall (all, 40-80 px, >= 80 px) and precision on the samples per model and mode;
    the int8 models decode with score threshold ``int8_score`` (fp32 with pedenv's 0.25)."""
    from pedenv.apps.evaluate_detections import evaluate_detections
    from pedenv.detection import create_detector
    from pedenv.detection.config import DetectionConfig

    for mode in modes:  # "far-nocascade": far without the cascade's verified low-score persons
        detection = DetectionConfig.named("far", cascade={"enabled": False}) if mode == "far-nocascade" else mode
        for name, path in models.items():
            score = 0.25 if name == "fp32" else int8_score
            backend = create_detector("onnx", model_path=path, detection=detection, threads=2,
                                          score_threshold=score)
            report = evaluate_detections(SAMPLES, detection=detection, backend=backend, threads=2)
            s = report["summary"]["all"]
            goal = {b["bin"]: b for b in s["by_goal_height"]}
            print(f"{mode:5s} {name:16s} score>{score:.2f} recall {s['recall']:.3f} ({s['found']}/{s['persons']})  "
                  f"40-80 px {goal['40-80']['recall']:.3f} ({goal['40-80']['found']}/{goal['40-80']['persons']})  "
                  f">=80 px {goal['>=80']['recall']:.3f}  precision {s['precision']:.3f} "
                  f"(FP {s['false_positives']})  ms/frame {s['ms_per_frame']:.0f}", flush=True)


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU matrix of boxes a (N, 4) and b (M, 4), px ``[u0, v0, u1, v1]``."""
    lt = np.maximum(a[:, None, :2], b[None, :, :2])
    rb = np.minimum(a[:, None, 2:], b[None, :, 2:])
    inter = np.prod(np.clip(rb - lt, 0, None), axis=2)
    area = lambda x: np.prod(x[:, 2:] - x[:, :2], axis=1)  # noqa: E731
    return inter / (area(a)[:, None] + area(b)[None, :] - inter + 1e-9)


def keypoint_gaps(reference: Path, other: Path) -> dict[str, float]:
    """Keypoint distance between two models' ``far`` detections of the same persons on the samples:
    persons matched greedily by IoU >= 0.5; keypoints seen by both (visibility > 0.5)."""
    from pedenv.detection import create_detector
    from pedenv.evaluation.detections import load_samples
    from pedenv.images import read_image_rgb

    backends = [create_detector("onnx", model_path=p, detection="far", threads=2) for p in (reference, other)]
    px, rel, persons, unmatched = [], [], 0, 0
    for sample in load_samples(SAMPLES):
        image = read_image_rgb(sample.image_path)
        a, b = (be.detect(image, sample.geometry) for be in backends)
        iou = _iou(a.boxes, b.boxes) if len(a.boxes) and len(b.boxes) else np.zeros((len(a.boxes), 0))
        used: set[int] = set()
        for i in np.argsort(-a.scores):
            j = int(np.argmax(iou[i])) if iou.shape[1] else -1
            if j < 0 or iou[i, j] < 0.5 or j in used:
                unmatched += 1
                continue
            used.add(j)
            persons += 1
            seen = (a.confidences[i] > 0.5) & (b.confidences[j] > 0.5)
            d = np.linalg.norm(a.keypoints[i][seen] - b.keypoints[j][seen], axis=1)
            px.extend(d)
            rel.extend(100 * d / max(a.boxes[i, 3] - a.boxes[i, 1], 1.0))
    return {"persons": persons, "unmatched_reference": unmatched, "keypoints": len(px),
            "mean_px": float(np.mean(px)), "p95_px": float(np.percentile(px, 95)),
            "mean_pct_height": float(np.mean(rel)), "p95_pct_height": float(np.percentile(rel, 95))}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=None, help="folder for the int8 models (default: a temp folder)")
    parser.add_argument("--frames", type=int, default=60, help="calibration frames of vtest.avi (2 inputs each)")
    parser.add_argument("--runs", type=int, default=40, help="timed passes per model and input size")
    parser.add_argument("--skip-eval", action="store_true", help="timing only: no recall or keypoints")
    parser.add_argument("--variants", default="int8,int8-heads-fp32", help=f"comma-separated, of {list(VARIANTS)}")
    parser.add_argument("--calibrate", default="minmax", choices=["minmax", "percentile"])
    parser.add_argument("--modes", default="fast,far", help="detection modes to evaluate (fast, far, far-nocascade)")
    parser.add_argument("--int8-score", type=float, default=0.25, help="int8 models' score threshold")
    parser.add_argument("--no-keypoints", action="store_true", help="skip the keypoint comparison")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="pedenv_int8_"))
    out.mkdir(parents=True, exist_ok=True)
    fp32 = find_onnx_model()
    inputs = calibration_inputs(args.frames)
    models = {"fp32": fp32}
    for name in args.variants.split(","):
        target = out / f"yolo11n-pose_{name}_{args.calibrate}.onnx"
        if not target.is_file():
            start = time.perf_counter()
            quantize(fp32, target, inputs, name, args.calibrate)
            print(f"{name}: quantized in {time.perf_counter() - start:.0f} s -> {target}", flush=True)
        models[name] = target
    print("load before timing:", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    medians = time_passes(models, args.runs)
    print("load after timing: ", subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip())
    for name, row in medians.items():
        print(f"{name:16s} " + "  ".join(f"{size} {ms:6.1f} ms (x{medians['fp32'][size] / ms:.2f})"
                                         for size, ms in row.items()))
    if args.skip_eval:
        return
    recall_rows(models, tuple(args.modes.split(",")), args.int8_score)
    for name in [] if args.no_keypoints else list(models)[1:]:
        print(f"keypoints fp32 vs {name} (far):", keypoint_gaps(fp32, models[name]), flush=True)


if __name__ == "__main__":
    main()
