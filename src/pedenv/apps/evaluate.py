"""Run the environment model over a dataset and evaluate it with the paper's protocol."""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import nullcontext
from dataclasses import replace
from pathlib import Path

import numpy as np

from pedenv.apps.progress import progress_bar
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.evaluation.matching import match_to_ground_truth, position_errors
from pedenv.evaluation.metrics import ErrorSamples, Metrics
from pedenv.evaluation.result import EvaluationResult
from pedenv.evaluation.tracking_metrics import TrackingAccumulator
from pedenv.geometry import inverse_2x2
from pedenv.io.datasets import Dataset
from pedenv.io.jsonl import EnvironmentWriter
from pedenv.io.outputs import write_outputs
from pedenv.io.sinks import ExtraOutputs
from pedenv.model import PedestrianEnvironmentModel
from pedenv.pose import PoseBackend, create_pose_backend
from pedenv.pose.redetect import with_redetection
from pedenv.records import Frame
from pedenv.state import EnvironmentState


def resolve_scenes(dataset: Dataset, scenes: Sequence[str] | None) -> list[str]:
    """The scenes to run: the named ones (checked), else the dataset's defaults (all by default)."""
    names = dataset.scene_names()
    if not scenes:
        return list(getattr(dataset, "default_scenes", dataset.scene_names)())
    unknown = [s for s in scenes if s not in names]
    if unknown:
        raise InputError(f"unknown scene(s) {', '.join(unknown)} in {dataset.name}; scenes there: {', '.join(names)}")
    return list(scenes)


def run_evaluation(dataset: Dataset, *, scenes: Sequence[str] | None = None, config: Config | None = None,
                   pose_backend: str | PoseBackend | None = None, output_dir: str | Path | None = None,
                   progress: bool = False, model_factory=PedestrianEnvironmentModel,
                   extra_outputs: ExtraOutputs | None = None) -> EvaluationResult:
    """Run every scene through a fresh model state, evaluate labelled frames, write outputs.

    Writes ``environment.jsonl`` line by line while running (when ``output_dir`` is set),
    so a failure at a bad frame keeps what was computed; ``metrics.json`` etc. come from
    :func:`pedenv.io.outputs.write_outputs`. ``extra_outputs``: Parquet, Rerun, MCAP, video
    (refused before the run when their extra is missing; closed, and so valid, when a frame fails).
    """
    config = config or Config()
    backend = _backend(pose_backend or dataset.default_pose_backend)
    names = resolve_scenes(dataset, scenes)
    model = model_factory(config)
    backend = with_redetection(backend, model, config.redetect)  # missed tracks searched in crops (fused)
    samples = {name: ErrorSamples() for name in names}
    tracking = TrackingAccumulator()
    busiest, busiest_n = None, -1
    writer = EnvironmentWriter(Path(output_dir) / "environment.jsonl") if output_dir else None
    extra_outputs = extra_outputs or ExtraOutputs()
    sinks = extra_outputs.open()
    pairs = _matches_writer(extra_outputs.matches_parquet, sinks)
    with progress_bar(enabled=progress) as bar, writer or nullcontext(), sinks, pairs or nullcontext():
        for name in names:
            frames = list(dataset.frames(name))
            task = bar.add_task(name, total=len(frames))
            model.reset()
            for frame in frames:
                frame = replace(frame, detections=backend(frame))
                state = model.update(frame)
                if writer:
                    writer.write(state)
                sinks.write(state, frame)
                if frame.ground_truth is not None:
                    n = _score(frame, state, samples[name], tracking, pairs)
                    if n > busiest_n:
                        busiest, busiest_n = (state, frame), n
                bar.advance(task)
    info = {"dataset": dataset.name, "pose_backend": backend.name, "method": config.method,
            "scenes": names}
    metrics = Metrics.from_samples(samples, tracking.summary(), model.timer.per_stage_ms(), info)
    files = sinks.files + ([pairs.path] if pairs else [])
    return EvaluationResult(metrics, samples, busiest, extras={"files": files})


def evaluate_dataset(dataset: Dataset, *, scenes: Sequence[str] | None = None, config: Config | None = None,
                     pose_backend: str | PoseBackend | None = None, output_dir: str | Path | None = None,
                     progress: bool = False, extra_outputs: ExtraOutputs | None = None) -> Metrics:
    """Evaluate ``dataset`` and, with ``output_dir``, write every output; returns the metrics."""
    result = run_evaluation(dataset, scenes=scenes, config=config, pose_backend=pose_backend,
                            output_dir=output_dir, progress=progress, extra_outputs=extra_outputs)
    if output_dir:
        write_outputs(result, Path(output_dir), config or Config())
    return result.metrics


def _score(frame: Frame, state: EnvironmentState, samples: ErrorSamples, tracking: TrackingAccumulator,
           pairs=None) -> int:
    gt, peds = frame.ground_truth, state.pedestrians
    if gt is None:
        raise InputError(f"frame {frame.index} of {frame.scene}: no ground truth to score against")
    tracking.add(frame.scene, gt.ids, gt.boxes, peds.track_ids, peds.boxes)
    match = match_to_ground_truth(peds.boxes, peds.positions[:, :2], gt.boxes, gt.positions[:, :2])
    sel = match >= 0
    if sel.any():
        pred, truth = peds.positions[sel, :2], gt.positions[match[sel], :2]
        abs_err, rel_err, dist = position_errors(pred, truth, frame.ego.translation[:2])
        e = pred - truth
        cov = peds.covariances[sel] + 1e-9 * np.eye(2)
        maha = np.sqrt(np.einsum("ni,nij,nj->n", e, inverse_2x2(cov), e))
        samples.add(abs_err, rel_err, dist, maha)
        if pairs is not None:
            pairs.write_pairs(frame, peds.track_ids[sel], gt.ids[match[sel]], pred, truth, abs_err, rel_err, dist)
    return int((sel & (peds.ages >= 3)).sum())  # settled tracks: what the busiest-frame plot shows


def _matches_writer(path, sinks):
    """The matched-pairs table writer, or None; closes ``sinks`` when it cannot be opened."""
    if not path:
        return None
    from pedenv.io.parquet import MatchesTableWriter

    try:
        return MatchesTableWriter(path)
    except BaseException:
        sinks.close()
        raise


def _backend(spec) -> PoseBackend:
    return create_pose_backend(spec) if isinstance(spec, str) else spec
