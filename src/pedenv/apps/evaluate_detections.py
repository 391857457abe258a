"""``pedenv evaluate-detections``: person recall and precision of the pose backend on real images.

Runs the ``onnx`` backend in a detection mode over the real samples (KITTI, MOT17,
nuScenes cameras), matches with :mod:`pedenv.evaluation.detections`, times each image
(network passes and merging, not reading the file) and writes ``detections_eval.json``.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pedenv.detection.config import STREAM_MIN_HITS
from pedenv.evaluation.detections import DetectionSample, load_samples, match_detections, summarize
from pedenv.evaluation.metrics import strict_json
from pedenv.images import read_image_rgb
from pedenv.records import Detections, PredictedTracks

if TYPE_CHECKING:
    from rich.table import Table

    from pedenv.detection import DetectionConfig, Detector


def evaluate_detections(data_root: str | Path, detection: str | DetectionConfig = "far",
                        output: str | Path | None = None, backend: Detector | None = None,
                        model_path: str | Path | None = None, threads: int = 2,
                        progress: Callable[[int, int], None] | None = None,
                        samples: list[DetectionSample] | None = None) -> dict:
    """Recall/precision report (a JSON-ready dict) of ``detection`` mode (``fast``, ``far`` or a
    DetectionConfig) on the samples under ``data_root``; written to ``output/detections_eval.json``
    when ``output`` is given. ``backend``: a :class:`~pedenv.detection.Detector` to use instead of creating one.
    ``samples``: a list of DetectionSample to use instead of all under ``data_root``.
    ``stream`` runs each sequence's samples as consecutive frames (:func:`stream_frame`).
    """
    from pedenv.detection import create_detector

    samples = load_samples(data_root) if samples is None else samples
    pose: Any = backend or create_detector("onnx", model_path=model_path, detection=detection, threads=threads)
    images = [read_image_rgb(s.image_path) for s in samples]
    pose.detect(images[0], samples[0].geometry)  # warm-up: onnxruntime's first run allocates
    matches, ms, cpu_ms, units = [], [], [], []
    previous: tuple[DetectionSample, Detections] | None = None
    for i, (sample, image) in enumerate(zip(samples, images)):
        start, cpu = time.perf_counter(), time.process_time()
        if pose.stream is not None:  # stream: a sequence's samples in order, consecutive frames
            dets = stream_frame(pose, image, sample, previous)
            previous = (sample, dets)
        else:
            dets = pose.detect(image, sample.geometry)
        ms.append(1e3 * (time.perf_counter() - start))
        cpu_ms.append(1e3 * (time.process_time() - cpu))
        units.append(network_units(pose))
        matches.append(match_detections(sample, dets.boxes, dets.scores))
        if progress:
            progress(i + 1, len(samples))
    report = {"data_root": str(data_root), "backend": pose.describe(), "threads": threads,
              "matching": "greedy by score, IoU >= 0.5 (nuScenes 0.3); MOT17 boxes clipped to the image",
              "timing": "ms: wall time per image (passes + merge); cpu_ms: process CPU time (all threads); "
                        "units: network input pixels per image / (384 x 640), a load-independent cost",
              "summary": summarize(samples, matches, ms),
              "cost": {d: {"cpu_ms_per_frame": _mean(cpu_ms, samples, d), "units_per_frame": _mean(units, samples, d)}
                       for d in ["all", *sorted({s.dataset for s in samples})]},
              "images": [{"dataset": s.dataset, "name": s.name, "persons": int(s.required.sum()),
                          "found": int(m.hit.sum()), "detections": m.detections,
                          "false_positives": m.false_positives if s.count_false_positives else None, "ms": t,
                          "cpu_ms": c, "units": u}
                         for s, m, t, c, u in zip(samples, matches, ms, cpu_ms, units)]}
    if output is not None:
        out = Path(output)
        out.mkdir(parents=True, exist_ok=True)
        (out / "detections_eval.json").write_text(json.dumps(strict_json(report), indent=2) + "\n")
    return report


def stream_frame(pose: Detector, image: np.ndarray, sample: DetectionSample,
                 previous: tuple[DetectionSample, Detections] | None) -> Detections:
    """``pose.detect_frame`` on one sample as the next frame of its sequence; the tracks stand-in
    is the previous sample's persons where it is the frame before in the same sequence (not moved,
    ``STREAM_MIN_HITS`` hits each); a sample of another sequence, or of none, restarts the stream.
    ``image``: (H, W, 3) uint8 RGB."""
    if previous is None or not sample.sequence or previous[0].sequence != sample.sequence:
        pose.restart()
        return pose.detect_frame(image, sample.geometry, sample.timestamp)
    boxes = previous[1].boxes
    hits = np.full(len(boxes), STREAM_MIN_HITS)
    tracks = PredictedTracks(np.arange(len(boxes)), boxes, hits)
    return pose.detect_frame(image, sample.geometry, sample.timestamp, tracks)


def network_units(pose: Detector) -> float:
    """Network input pixels of the passes ``pose`` ran on its last image, in units of one
    384x640 pass (a load-independent cost; `pedenv bench` times one such pass on this machine)."""
    return sum(p.input_size[0] * p.input_size[1] for p in pose.last_passes) / (384 * 640)


def _mean(values: list[float], samples: list[DetectionSample], dataset: str) -> float:
    picked = [v for v, s in zip(values, samples) if dataset in ("all", s.dataset)]
    return float(sum(picked) / len(picked)) if picked else float("nan")


def _pct(x: float | None) -> str:
    return "-" if x is None else f"{100 * x:.0f} %"


def detection_table(report: dict, title: str = "") -> Table:
    """A rich table: recall by height (and goal bins), precision, ms per frame, per dataset."""
    from rich.table import Table

    summary = report["summary"]
    heights = [b["bin"] for b in summary["all"]["by_height"]]
    goals = [b["bin"] for b in summary["all"]["by_goal_height"]]
    table = Table(title=title or "person detection on real images")
    for col in ["dataset", "images", "persons", *[f"{h} px" for h in heights], *[f"{g} px" for g in goals],
                "recall", "precision", "ms/frame", "cpu ms", "units"]:
        table.add_column(col, justify="left" if col == "dataset" else "right")
    for name, block in summary.items():
        cells = [
            f"{_pct(b['recall'])} ({b['found']}/{b['persons']})" for b in block["by_height"] + block["by_goal_height"]
        ]
        table.add_row(
            name,
            str(block["images"]),
            str(block["persons"]),
            *cells,
            _pct(block["recall"]),
            _pct(block["precision"]),
            f"{block['ms_per_frame']:.0f}",
            f"{report['cost'][name]['cpu_ms_per_frame']:.0f}",
            f"{report['cost'][name]['units_per_frame']:.1f}",
        )
    return table


def distance_table(report: dict) -> Table:
    """A rich table: recall by distance bin where 3D ground truth exists (KITTI, nuScenes)."""
    from rich.table import Table

    summary = report["summary"]
    table = Table(title="recall by distance (3D ground truth)")
    bins = [b["bin"] for b in summary["all"]["by_distance"]]
    for col in ["dataset", *[f"{b} m" for b in bins]]:
        table.add_column(col, justify="left" if col == "dataset" else "right")
    for name, block in summary.items():
        if any(b["persons"] for b in block["by_distance"]):
            table.add_row(name, *[f"{_pct(b['recall'])} ({b['found']}/{b['persons']})" for b in block["by_distance"]])
    return table
