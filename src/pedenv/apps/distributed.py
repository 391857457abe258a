"""Evaluation over many scenes on an executor (serial or Ray), one task per scene.

    with create_executor("ray", workers=2) as ex:
        result = evaluate_on(dataset, executor=ex, output_dir="out")

Each scene is one :func:`~pedenv.apps.scene_result.evaluate_scene` on a worker; the pose
backend is made once per worker process and kept for its later scenes. The results are
merged in scene order by :func:`~pedenv.apps.scene_result.merge_scene_results`, so
``metrics.json`` holds the numbers of a serial run to the last digit, all but the stage
timings (wall times). With ``output_dir`` each finished scene is saved at once under
``scenes/<name>/`` (its ``environment.jsonl`` and a ``result.npz`` checkpoint of plain arrays,
:mod:`pedenv.apps.scene_checkpoint`); at the end
``environment.jsonl`` is their concatenation in scene order, as a serial run writes it.
A scene that raises is reported by name in ``result.extras["failures"]`` and in
``metrics.json``'s ``info.failed_scenes``; the others finish and are written.
``resume`` reuses the checkpoints of an earlier run in ``output_dir`` and runs the rest.
The checkpoints are data, read without pickle: a forged one gives a clear error, never runs
code. A checkpoint of another run (another method, config, pose backend or dataset) is
refused with a line naming the scene, never merged.
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Sequence
from pathlib import Path

from pedenv.apps.evaluate import evaluation_info, resolve_scenes
from pedenv.apps.executors import RayExecutor, SerialExecutor, TaskContext
from pedenv.apps.options import ExecutorOptions
from pedenv.apps.progress import FrameCounter, progress_bar
from pedenv.apps.scene_checkpoint import load_checkpoint, run_identity, save_checkpoint
from pedenv.apps.scene_result import SceneHooks, SceneResult, evaluate_scene, merge_scene_results
from pedenv.config import Config
from pedenv.datasets import Dataset
from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.evaluation.result import EvaluationResult
from pedenv.outputs.jsonl import EnvironmentWriter
from pedenv.pose.base import PoseBackend

#: Folder of the per-scene outputs and checkpoints inside the output folder.
SCENES_FOLDER = "scenes"
CHECKPOINT = "result.npz"
#: The pickle checkpoint of pedenv before issue 19: never opened (unpickling can run code).
PICKLE_CHECKPOINT = "result.pkl"

#: A pose backend as workers get it: a registered name, a picklable backend, or a
#: picklable factory (``functools.partial(create_detector, "onnx", detection="far")``).
BackendSpec = str | PoseBackend | Callable[[], PoseBackend]


def make_backend(spec: BackendSpec, config: Config) -> PoseBackend:
    """The backend of ``spec``: created by name (onnx: with ``config``'s merge and re-detection
    settings), called as a factory, or ``spec`` itself."""
    if isinstance(spec, str):
        return create_detector(spec, redetect=config.redetect)
    if isinstance(spec, PoseBackend):
        return spec
    return spec()


def evaluate_on(dataset: Dataset, *, executor: SerialExecutor | RayExecutor, scenes: Sequence[str] | None = None,
                config: Config | None = None, pose_backend: BackendSpec | None = None,
                output_dir: str | Path | None = None, resume: bool = False,
                progress: bool = False) -> EvaluationResult:
    """Evaluate the scenes of ``dataset`` as tasks of ``executor`` (entered by the caller).

    ``pose_backend`` is made here once (to check it and name it) and once per worker.
    Returns the merged result of the scenes that finished; ``extras["failures"]`` maps
    each failed scene to its exception, ``extras["resumed"]`` lists the reused scenes.
    """
    config = config or Config()
    spec = pose_backend or dataset.default_pose_backend
    backend = make_backend(spec, config)
    names = resolve_scenes(dataset, scenes)
    run = run_identity(dataset.name, backend.name, config.to_dict())
    store = SceneStore(Path(output_dir), run) if output_dir else None
    finished: dict[str, SceneResult] = store.load(names) if (store and resume) else {}
    resumed = list(finished)
    failures: dict[str, BaseException] = {}
    todo = [n for n in names if n not in finished]
    shared = {"dataset": dataset, "config": config, "backend": spec}
    with progress_bar(enabled=progress) as bar:
        counter = FrameCounter(bar, len(names), already=len(finished))
        for name, value, error in executor.run(_scene_task, todo, shared=shared, on_progress=counter.update):
            if error is not None:
                failures[name] = error
            else:
                if store:
                    store.save(value)
                value.lines = None
                finished[name] = value
            counter.finish(name, failed=error is not None)
    info = evaluation_info(dataset, backend, config, names)
    if failures:
        info["failed_scenes"] = {n: f"{type(e).__name__}: {e}" for n, e in failures.items()}
    result = merge_scene_results([finished[n] for n in names if n in finished], info)
    if store:
        store.concatenate([n for n in names if n in finished])
    result.extras.update(failures=failures, resumed=resumed)
    return result


def _scene_task(name: str, context: TaskContext) -> SceneResult:
    """One scene on a worker: the dataset's frames through a fresh model, lines collected."""
    dataset, config, spec = (context.shared[k] for k in ("dataset", "config", "backend"))
    backend = context.cached(("backend", id(spec)), lambda: make_backend(spec, config))
    frames = list(dataset.frames(name))
    context.report(0, len(frames))
    hooks = SceneHooks(collect_lines=True, progress=lambda done: context.report(done, len(frames)))
    return evaluate_scene(name, frames, config=config, backend=backend, hooks=hooks)


class SceneStore:
    """The per-scene outputs of an output folder: ``scenes/<name>/environment.jsonl`` and its checkpoint.

    run: what the checkpoints must share with this run (:func:`~pedenv.apps.scene_checkpoint.run_identity`).
    """

    def __init__(self, output_dir: Path, run: dict) -> None:
        self.root = output_dir / SCENES_FOLDER
        self.output_dir = output_dir
        self.run = run

    def folder(self, name: str) -> Path:
        if not name or "/" in name or "\\" in name or name in (".", ".."):
            raise InputError(f"scene name {name!r} cannot name a folder")
        return self.root / name

    def save(self, result: SceneResult) -> None:
        """Write the scene's lines, then its checkpoint (last, atomically: it marks the scene complete)."""
        folder = self.folder(result.name)
        with EnvironmentWriter(folder / "environment.jsonl") as writer:
            for line in result.lines or []:
                writer.write_line(line)
        save_checkpoint(folder / CHECKPOINT, result, self.run)

    def load(self, names: Sequence[str]) -> dict[str, SceneResult]:
        """The checkpoints of the scenes among ``names`` that an earlier run completed
        (InputError naming the scene for a checkpoint that is damaged, of another run, or a
        pickle of an older pedenv, which is never opened)."""
        found = {}
        for name in names:
            folder = self.folder(name)
            path = folder / CHECKPOINT
            if not path.is_file() and (folder / PICKLE_CHECKPOINT).is_file():
                raise InputError(f"{folder / PICKLE_CHECKPOINT}: a checkpoint of an older pedenv, a Python pickle, "
                                 f"which pedenv no longer opens (unpickling can run code); delete {folder} to run "
                                 f"scene {name} again")
            if path.is_file() and (folder / "environment.jsonl").is_file():
                found[name] = load_checkpoint(path, name, self.run)
        return found

    def concatenate(self, names: Sequence[str]) -> Path:
        """``environment.jsonl`` of the output folder: the scenes' files in the order of ``names``."""
        path = self.output_dir / "environment.jsonl"
        with path.open("wb") as out:
            for name in names:
                with (self.folder(name) / "environment.jsonl").open("rb") as part:
                    shutil.copyfileobj(part, out)
        return path


def evaluate_distributed(dataset: Dataset, *, executor: ExecutorOptions | None = None,
                         scenes: Sequence[str] | None = None, config: Config | None = None,
                         pose_backend: BackendSpec | None = None, output_dir: str | Path | None = None,
                         overwrite: bool = False, progress: bool = False) -> EvaluationResult:
    """:func:`evaluate_on` with the executor ``executor`` names (started and stopped here; default: a
    local Ray), then ``metrics.json``, ``config.json`` and the plots into ``output_dir`` (also when
    scenes failed).

    ``output_dir`` must be new, empty, a folder pedenv wrote with ``overwrite`` (emptied), or
    one it wrote with ``executor.resume`` (continued).
    """
    from pedenv.apps.evaluation_outputs import write_outputs
    from pedenv.apps.executors import create_executor
    from pedenv.outputs.output_dir import prepare_output_dir

    config = config or Config()
    executor = executor or ExecutorOptions("ray")
    if output_dir is not None:
        if executor.resume:
            prepare_resume_dir(Path(output_dir))
        else:
            prepare_output_dir(output_dir, overwrite=overwrite, command="pedenv evaluate")
    with create_executor(executor.name, address=executor.address, workers=executor.workers,
                         object_store_memory=executor.object_store_memory) as ex:
        result = evaluate_on(dataset, executor=ex, scenes=scenes, config=config, pose_backend=pose_backend,
                             output_dir=output_dir, resume=executor.resume, progress=progress)
    if output_dir is not None:
        result.extras["paths"] = write_outputs(result, Path(output_dir), config)
    return result


def prepare_resume_dir(path: Path) -> Path:
    """``path`` for a resumed run: created if new; a non-empty folder must be pedenv's own."""
    from pedenv.outputs.output_dir import MARKER, prepare_output_dir

    if path.is_dir() and any(path.iterdir()):
        if not (path / MARKER).is_file():
            raise InputError(f"output folder {path} is not empty and was not written by pedenv (no {MARKER} "
                             f"file): --resume continues pedenv's own runs only")
        return path
    return prepare_output_dir(path, command="pedenv evaluate --resume")
