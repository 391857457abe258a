"""Run several position methods on the same frames and put their results side by side.

    results = compare_methods(dataset, methods=("paper", "fused"), output_dir="out")
    console.print(comparison_by_scene_table(results))
    console.print(comparison_summary_table(results))

Each method gets its own model but the same pose backend object, so both see the same
detections. With ``output_dir`` every method's usual outputs go to ``output_dir/<method>/``
and ``output_dir`` gets one ``error_by_distance.png`` with all methods and a combined
``metrics.json`` ``{"methods": {name: metrics}}``. :func:`outputs_per_method` names each
method's Parquet, Rerun and MCAP files.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

from rich.table import Table

from pedenv.apps.evaluate import run_evaluation
from pedenv.apps.evaluation_outputs import write_outputs
from pedenv.config import Config
from pedenv.datasets import Dataset
from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.evaluation.metrics import ErrorSummary, strict_json
from pedenv.evaluation.report import fmt
from pedenv.evaluation.result import EvaluationResult
from pedenv.localization import METHODS, configure
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.pose.base import PoseBackend
from pedenv.visualize.plots import plot_error_by_distance


def compare_methods(
    dataset: Dataset,
    *,
    methods: Sequence[str] = ("paper", "fused"),
    scenes: Sequence[str] | None = None,
    config: Config | None = None,
    pose_backend: str | PoseBackend | None = None,
    output_dir: str | Path | None = None,
    progress: bool = False,
    extra_outputs: Mapping[str, ExtraOutputs] | None = None,
) -> dict[str, EvaluationResult]:
    """Evaluate each of ``methods`` (``Config.method`` values) on the same frames.

    ``config`` supplies everything but the method. ``extra_outputs``: method -> its
    Parquet, Rerun and MCAP outputs (:func:`outputs_per_method`); all are checked before
    the first method runs. Returns method -> result, in order.
    Raises ValueError for an unknown or repeated method.
    """
    methods = list(methods)
    unknown = [m for m in methods if m not in METHODS]
    if unknown or not methods or len(set(methods)) != len(methods):
        raise InputError(f"methods must be distinct names from {', '.join(METHODS)}, got {methods}")
    config = config or Config()
    spec = pose_backend or dataset.default_pose_backend
    backend = create_detector(spec) if isinstance(spec, str) else spec
    out = Path(output_dir) if output_dir else None
    extras = dict(extra_outputs or {})
    for extra in extras.values():
        extra.check()
    results: dict[str, EvaluationResult] = {}
    for method in methods:
        cfg = configure(config, method)
        where = out / method if out else None
        results[method] = run_evaluation(dataset, scenes=scenes, config=cfg, pose_backend=backend,
                                         output_dir=where, progress=progress, extra_outputs=extras.get(method))
        if where:
            write_outputs(results[method], where, cfg, label=method)
    if out:
        write_comparison(results, out)
    return results


def outputs_per_method(extra: ExtraOutputs, methods: Sequence[str], output_dir: str | Path) -> dict[str, ExtraOutputs]:
    """``extra`` for each method of a comparison: the Parquet tables and the video in that
    method's folder (``output_dir/<method>/environment.parquet``, ``matches.parquet``), the
    Rerun, MCAP and ROS files with the method in their name (``run.rrd`` -> ``run-paper.rrd``).
    """
    def in_folder(path: Path | None, method: str) -> Path | None:
        return None if path is None else Path(output_dir) / method / path.name

    def tagged(path: Path | None, method: str) -> Path | None:
        return None if path is None else path.with_name(f"{path.stem}-{method}{path.suffix}")

    return {m: replace(extra, parquet=in_folder(extra.parquet, m), matches_parquet=in_folder(extra.matches_parquet, m),
                       birds_eye_video=in_folder(extra.birds_eye_video, m), rerun=tagged(extra.rerun, m),
                       mcap=tagged(extra.mcap, m), ros=tagged(extra.ros, m))
            for m in methods}


def write_comparison(results: dict[str, EvaluationResult], output_dir: Path) -> dict[str, Path]:
    """``error_by_distance.png`` with every method and ``metrics.json`` ``{"methods": {...}}``."""
    output_dir.mkdir(parents=True, exist_ok=True)
    first = next(iter(results.values())).metrics.info
    plot = plot_error_by_distance({m: r.metrics.error_by_distance for m, r in results.items()},
                                  output_dir / "error_by_distance.png",
                                  title=f"Absolute error over distance ({first.get('dataset', '')}, "
                                        f"{first.get('pose_backend', '')})")
    metrics = output_dir / "metrics.json"
    data = {"methods": {m: r.metrics.to_dict() for m, r in results.items()}}
    metrics.write_text(json.dumps(strict_json(data), indent=2, allow_nan=False) + "\n")
    return {"error_by_distance": plot, "metrics": metrics}


def comparison_by_scene_table(results: dict[str, EvaluationResult], title: str = "") -> Table:
    """Relative and absolute error of every method, overall then per scene, side by side."""
    first = next(iter(results.values())).metrics
    table = Table(title=title or f"{first.info.get('dataset', '')} ({first.info.get('pose_backend', '')}): "
                                 + " vs ".join(results))
    table.add_column("Scene")
    for m in results:
        table.add_column(f"{m} rel. [%]", justify="right")
        table.add_column(f"{m} abs. [m]", justify="right")
    table.add_column("# Pedestrians", justify="right")
    per_method = {m: dict(r.metrics.scenes) for m, r in results.items()}
    overall: dict[str, ErrorSummary | None] = {m: r.metrics.overall for m, r in results.items()}
    rows = [("all", overall)]
    rows += [(name, {m: per_method[m].get(name) for m in results}) for name, _ in first.scenes]
    for name, cells in rows:
        values = []
        for m in results:
            s = cells[m]
            values += [fmt(s.rel_error_pct if s else None, 2), fmt(s.abs_error_m if s else None, 3)]
        count = cells[next(iter(results))]
        table.add_row(name, *values, str(count.count if count else 0), style="bold" if name == "all" else None)
    return table


def comparison_summary_table(results: dict[str, EvaluationResult], title: str = "") -> Table:
    """Per method: overall errors, calibration of the covariance, tracking quality, timings."""
    table = Table(title=title or "Methods compared")
    for col in ("Method", "Rel. error [%]", "Abs. error [m]", "Within 1 sigma [%] (39.3)",
                "Within 2 sigma [%] (86.5)", "MOTA", "Position [ms/ped]", "Tracking [ms/frame]"):
        table.add_column(col, justify="left" if col == "Method" else "right")
    for m, r in results.items():
        mt = r.metrics
        cal, trk, tm = mt.calibration, mt.tracking or {}, mt.timing_ms
        table.add_row(m, fmt(mt.overall.rel_error_pct, 2), fmt(mt.overall.abs_error_m, 3),
                      fmt(100 * cal.get("within_1sigma", float("nan")), 1),
                      fmt(100 * cal.get("within_2sigma", float("nan")), 1), fmt(trk.get("mota"), 3),
                      fmt(tm.get("position_per_pedestrian"), 3), fmt(tm.get("tracking_per_frame"), 3))
    return table
