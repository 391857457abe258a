"""``pedenv demo``: the built-in synthetic scenes through the whole method, evaluated and drawn."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

from pedenv.apps.evaluate import run_evaluation
from pedenv.apps.evaluation_outputs import write_outputs
from pedenv.apps.options import MethodOptions, OutputFlags, OutputOptions
from pedenv.config import Config
from pedenv.datasets.memory import MemoryDataset
from pedenv.errors import InputError
from pedenv.evaluation.result import EvaluationResult
from pedenv.localization import configure
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.records import Scene
from pedenv.visualize.plots import plot_error_by_distance

#: The most scenes ``builtin_scenes`` / ``pedenv simulate --scenes`` makes in one go (each
#: is 15-20 s of frames; 1000 of them take about an hour and some GB on disk).
MAX_SCENES = 1000
#: The methods the demo puts side by side, on the same frames and detections.
DEMO_METHODS = ("paper", "fused")
#: The scene of the demo's animated bird's-eye view (the busiest: 37 people per frame on average).
VIDEO_SCENE = "crowd"


def builtin_scenes(seed: int = 0, count: int | None = None, *, terrain: bool = False,
                   frame_rate_hz: float = 10.0) -> list[Scene]:
    """``count`` built-in scenes (all scenarios once by default; more repeat them with new seeds).

    Scenes beyond the first round are named ``<scenario>-<k>``.
    """
    return list(iter_builtin_scenes(seed, count, terrain=terrain, frame_rate_hz=frame_rate_hz))


def iter_builtin_scenes(seed: int = 0, count: int | None = None, *, terrain: bool = False,
                        frame_rate_hz: float = 10.0) -> Iterator[Scene]:
    """The scenes of :func:`builtin_scenes`, made one at a time as they are asked for
    (each scene depends only on its seed and scenario, so the scenes are the same).
    ``count`` must be in [1, :data:`MAX_SCENES`]."""
    from pedenv.synthetic import SCENARIOS, generate_scenes

    n = len(SCENARIOS) if count is None else count
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_SCENES:
        raise InputError(f"the number of scenes must be an integer in [1, {MAX_SCENES}], got {count!r}")
    generate_scenes(seed, [], terrain=terrain, frame_rate_hz=frame_rate_hz)  # checks the options up front
    return _scene_stream(seed, n, terrain, frame_rate_hz, list(SCENARIOS))


def _scene_stream(seed: int, n: int, terrain: bool, frame_rate_hz: float, scenarios: list[str]) -> Iterator[Scene]:
    from pedenv.synthetic import generate_scenes

    for k in range(n):
        round_, name = divmod(k, len(scenarios))
        (scene,) = generate_scenes(seed + round_, [scenarios[name]], terrain=terrain, frame_rate_hz=frame_rate_hz)
        yield scene if round_ == 0 else rename_scene(scene, f"{scene.name}-{round_}")


def rename_scene(scene: Scene, name: str) -> Scene:
    """The same scene under another name (its frames too)."""
    return Scene(name, tuple(replace(f, scene=name) for f in scene.frames), scene.description)


def run_demo(output_dir: str | Path, *, seed: int = 0, config: Config | None = None, terrain: bool = False,
             pose_backend: str = "detector-model", progress: bool = True,
             extra_outputs: ExtraOutputs | None = None, compare: bool = True) -> EvaluationResult:
    """Generate the built-in scenes, run and evaluate the model, write every output.

    The outputs (``metrics.json``, ``environment.jsonl``, plots, ``extra_outputs``) come
    from ``config``'s method (``fused`` by default). With ``compare`` every other method of
    :data:`DEMO_METHODS` runs on the same frames and detections too, for its metrics
    (``metrics-<method>.json``); ``error_by_distance.png`` then shows every method, and
    ``result.extras["methods"]`` maps each method, in :data:`DEMO_METHODS` order, to its
    EvaluationResult (for :func:`pedenv.apps.compare.comparison_by_scene_table`).

    ``extra_outputs``: Parquet, Rerun, MCAP; by default the bird's-eye video ``birds_eye.mp4``
    alone, of the scene :data:`VIDEO_SCENE`.
    """
    config = config or Config()
    output_dir = Path(output_dir)
    scenes = builtin_scenes(seed, terrain=terrain)
    dataset = MemoryDataset(scenes, name="synthetic", default_pose_backend=pose_backend)
    extra_outputs = extra_outputs or ExtraOutputs(birds_eye_video=output_dir / "birds_eye.mp4",
                                                  birds_eye_scene=VIDEO_SCENE)
    result = run_evaluation(dataset, config=config, output_dir=output_dir, progress=progress,
                            extra_outputs=extra_outputs)
    result.extras["paths"] = write_outputs(result, output_dir, config)
    if not compare:
        return result
    methods = {config.method: result}
    for method in (m for m in DEMO_METHODS if m != config.method):
        other = run_evaluation(dataset, config=configure(config, method), progress=progress)
        other.metrics.save(output_dir / f"metrics-{method}.json")
        methods[method] = other
    result.extras["methods"] = {m: methods[m] for m in sorted(methods, key=_demo_order)}
    result.extras["paths"]["error_by_distance"] = plot_error_by_distance(
        {m: r.metrics.error_by_distance for m, r in result.extras["methods"].items()},
        output_dir / "error_by_distance.png", title="Absolute error over distance (synthetic)")
    return result


def demo_command(*, output: OutputOptions, flags: OutputFlags, method: MethodOptions, seed: int = 0,
                 terrain: bool = False, pose_backend: str = "detector-model") -> EvaluationResult:
    """``pedenv demo``: :func:`run_demo` into ``output.folder`` with the command's outputs (``flags``,
    the bird's-eye video of :data:`VIDEO_SCENE`), after the outputs and the folder are checked."""
    from pedenv.apps.output_safety import list_files, outside_files, prepare_folder

    config = method.load()
    extra = flags.extra_outputs(output, matches=True, video_scene=VIDEO_SCENE)
    extra.check()
    given = method.config if isinstance(method.config, (str, Path)) else None
    folder = prepare_folder(output.folder, [("--config", given)], extra, overwrite=output.overwrite,
                            command="pedenv demo")
    try:
        with outside_files(folder, extra) as extra:  # earlier files outside the folder replaced at the end
            return run_demo(folder, seed=seed, config=config, terrain=terrain, pose_backend=pose_backend,
                            extra_outputs=extra)
    finally:
        list_files(folder, "pedenv demo")  # what a later --overwrite may delete


def simulate_command(*, output: OutputOptions, scenes: int | None = None, seed: int = 0, fmt: str = "synthetic",
                     terrain: bool = False, frame_rate: float | None = None) -> SceneCounter:
    """``pedenv simulate``: the built-in scenes written to ``output.folder`` in format ``fmt``
    (:data:`pedenv.datasets.SCENE_WRITERS`), each as it is made, at ``frame_rate`` Hz (default 10,
    12 for nuscenes); the format and the options are checked before the folder is prepared.
    Returns what was written, counted."""
    from pedenv.datasets import scene_writer
    from pedenv.outputs.output_dir import prepare_output_dir

    write = scene_writer(fmt)
    rate = frame_rate if frame_rate is not None else (12.0 if fmt == "nuscenes" else 10.0)
    stream = iter_builtin_scenes(seed, scenes, terrain=terrain, frame_rate_hz=rate)
    prepare_output_dir(output.folder, overwrite=output.overwrite, command="pedenv simulate")
    counter = SceneCounter()
    write((counter.add(scene) for scene in stream), Path(output.folder))
    return counter


def _demo_order(method: str) -> int:
    return DEMO_METHODS.index(method) if method in DEMO_METHODS else len(DEMO_METHODS)


class SceneCounter:
    """Counts scenes, frames and labelled pedestrians as scenes stream past."""

    def __init__(self) -> None:
        self.scenes = self.frames = self.pedestrians = 0

    def add(self, scene: Scene) -> Scene:
        self.scenes += 1
        self.frames += len(scene)
        self.pedestrians += sum(len(f.ground_truth) for f in scene.frames if f.ground_truth is not None)
        return scene

    def summary(self) -> str:
        return f"{self.scenes} scenes, {self.frames} frames, {self.pedestrians} visible pedestrians"
