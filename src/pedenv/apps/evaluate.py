"""Run the environment model over a dataset and evaluate it with the paper's protocol."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from contextlib import nullcontext
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from pedenv.apps.evaluation_outputs import write_outputs
from pedenv.apps.progress import progress_bar
from pedenv.apps.scene_result import SceneHooks, evaluate_scene, merge_scene_results
from pedenv.behaviour.conflict import CONFLICT_PROBABILITY
from pedenv.config import Config
from pedenv.datasets import Dataset
from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.evaluation.metrics import Metrics
from pedenv.evaluation.result import EvaluationResult
from pedenv.model import PedestrianEnvironmentModel
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.outputs.sinks import ExtraOutputs, Sinks
from pedenv.pose.base import PoseBackend
from pedenv.records import Frame
from pedenv.state import EnvironmentState

if TYPE_CHECKING:
    from rich.progress import Progress, TaskID

    from pedenv.outputs.parquet import MatchesTableWriter


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
                   progress: bool = False,
                   model_factory: Callable[[Config], PedestrianEnvironmentModel] = PedestrianEnvironmentModel,
                   extra_outputs: ExtraOutputs | None = None) -> EvaluationResult:
    """Run every scene through a fresh model state, evaluate labelled frames, write outputs (in this process).

    Writes ``environment.jsonl`` line by line while running (when ``output_dir`` is set),
    so a failure at a bad frame keeps what was computed; ``metrics.json`` etc. come from
    :func:`pedenv.apps.evaluation_outputs.write_outputs`. ``extra_outputs``: Parquet, Rerun, MCAP, video
    (refused before the run when their extra is missing; closed, and so valid, when a frame fails).
    Each scene is one :func:`~pedenv.apps.scene_result.evaluate_scene`, merged as the Ray
    executor merges them (:mod:`pedenv.apps.distributed`).
    """
    config = config or Config()
    backend = _backend(pose_backend or dataset.default_pose_backend, config)
    names = resolve_scenes(dataset, scenes)
    writer = EnvironmentWriter(Path(output_dir) / "environment.jsonl") if output_dir else None
    extra_outputs = extra_outputs or ExtraOutputs()
    sinks = extra_outputs.open()
    pairs = _matches_writer(extra_outputs.matches_parquet, sinks)
    results = []

    def on_frame(state: EnvironmentState, frame: Frame) -> None:
        if writer:
            writer.write(state)
        sinks.write(state, frame)

    with progress_bar(enabled=progress) as bar, writer or nullcontext(), sinks, pairs or nullcontext():
        for name in names:
            frames = list(dataset.frames(name))
            task = bar.add_task(name, total=len(frames))
            hooks = SceneHooks(on_frame=on_frame, pairs=pairs, progress=partial(_advance, bar, task))
            results.append(evaluate_scene(name, frames, config=config, backend=backend, model_factory=model_factory,
                                          hooks=hooks))
    result = merge_scene_results(results, evaluation_info(dataset, backend, config, names),
                                 CONFLICT_PROBABILITY)
    result.extras["files"] = sinks.files + ([pairs.path] if pairs else [])
    return result


def evaluation_info(dataset: Dataset, backend: PoseBackend, config: Config, names: Sequence[str]) -> dict:
    """The ``info`` of ``metrics.json``: dataset, pose backend, method and scenes; where the dataset
    says what its figures are (``perception``, e.g. skeletons rendered from labels), that too."""
    info = {"dataset": dataset.name, "pose_backend": backend.name, "method": config.method, "scenes": list(names)}
    perception = getattr(dataset, "perception", None)
    if perception:
        info["perception"] = perception
    return info


def evaluate_dataset(dataset: Dataset, *, scenes: Sequence[str] | None = None, config: Config | None = None,
                     pose_backend: str | PoseBackend | None = None, output_dir: str | Path | None = None,
                     progress: bool = False, extra_outputs: ExtraOutputs | None = None) -> Metrics:
    """Evaluate ``dataset`` and, with ``output_dir``, write every output; returns the metrics."""
    result = run_evaluation(dataset, scenes=scenes, config=config, pose_backend=pose_backend,
                            output_dir=output_dir, progress=progress, extra_outputs=extra_outputs)
    if output_dir:
        write_outputs(result, Path(output_dir), config or Config())
    return result.metrics


def _advance(bar: Progress, task: TaskID, done: int) -> None:
    bar.update(task, completed=done)


def _matches_writer(path: Path | None, sinks: Sinks) -> MatchesTableWriter | None:
    """The matched-pairs table writer, or None; closes ``sinks`` when it cannot be opened."""
    if not path:
        return None
    from pedenv.outputs.parquet import MatchesTableWriter

    try:
        return MatchesTableWriter(path)
    except BaseException:
        sinks.close()
        raise


def _backend(spec: str | PoseBackend, config: Config) -> PoseBackend:
    """The backend ``spec`` names (onnx: with the run's merge and re-detection settings), or ``spec``."""
    return create_detector(spec, redetect=config.redetect) if isinstance(spec, str) else spec
