"""How fast the pose backends are on one 1600x900 frame (nuScenes' camera size).

The paper reports 39.94 ms for its network and 40.54 ms for the whole model per frame
(GPU). Times here are end to end: letterbox, network, decoding and NMS.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.validation import check_count

if TYPE_CHECKING:
    from pedenv.pose.onnx_backend import OnnxPose
    from pedenv.pose.ultralytics_backend import UltralyticsPose

FRAME_SIZE = (900, 1600)  # (height, width)


def benchmark_image() -> np.ndarray:
    """(900, 1600, 3) uint8 RGB: ultralytics' street photo ``bus.jpg`` resized, else seeded noise."""
    try:
        import importlib.util

        spec = importlib.util.find_spec("ultralytics")
        locations = spec.submodule_search_locations if spec else None
        path = Path(list(locations)[0]) / "assets" / "bus.jpg" if locations else None
    except (ImportError, ValueError):
        path = None
    if path is not None and path.is_file():
        from pedenv.images import read_image_rgb

        return cv2.resize(read_image_rgb(path), (FRAME_SIZE[1], FRAME_SIZE[0]), interpolation=cv2.INTER_LINEAR)
    return np.random.default_rng(0).integers(0, 256, (*FRAME_SIZE, 3), dtype=np.uint8)


def time_detect(backend: OnnxPose | UltralyticsPose, image: np.ndarray, repeats: int = 10, warmup: int = 2) -> dict:
    """Milliseconds per ``backend.detect(image)``: mean, median and min over ``repeats`` runs."""
    for _ in range(warmup):
        backend.detect(image)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        backend.detect(image)
        times.append(1e3 * (time.perf_counter() - start))
    return {"ms_per_frame": float(np.mean(times)), "ms_median": float(np.median(times)),
            "ms_min": float(np.min(times)), "repeats": repeats}


def benchmark_pose(repeats: int = 10, threads: int = 2, device: str = "auto") -> list[dict]:
    """Time the pose backends on a 1600x900 frame, pre- and post-processing included.

    Rows (one per backend and input size): ``backend``, ``input_size`` ("HxW"),
    ``ms_per_frame`` (mean), ``ms_median``, ``ms_min``, ``repeats``, ``persons`` found, and the
    onnxruntime ``provider`` that ran it (``device``: auto, cpu or cuda, :mod:`pedenv.pose.providers`);
    a backend that cannot run here (no prepared model, no ultralytics) gets ``ms_per_frame``
    None and the reason in ``skipped``.
    """
    check_count("repeats", repeats, 1, 10000)
    os.environ["YOLO_OFFLINE"] = "1"
    from pedenv.pose.onnx_backend import OnnxPose

    image = benchmark_image()
    runs: list[tuple[str, tuple[int, int], Callable[[], OnnxPose | UltralyticsPose]]] = [
            ("onnx", (640, 640), lambda: OnnxPose(input_size=(640, 640), threads=threads, device=device)),
            ("onnx", (384, 640), lambda: OnnxPose(input_size=(384, 640), threads=threads, device=device)),
            ("ultralytics", (640, 640), _ultralytics)]
    rows = []
    for name, size, make in runs:
        row: dict[str, object] = {"backend": name, "input_size": f"{size[0]}x{size[1]}"}
        try:
            backend = make()
        except (InputError, ImportError) as exc:
            rows.append({**row, "ms_per_frame": None, "skipped": str(exc)})
            continue
        rows.append({**row, **time_detect(backend, image, repeats), "persons": len(backend.detect(image)),
                     "provider": getattr(backend, "provider", "torch, CPU")})
    return rows


def _ultralytics() -> UltralyticsPose:
    from pedenv.pose.ultralytics_backend import UltralyticsPose

    return UltralyticsPose(input_size=640)
