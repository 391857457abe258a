"""``pedenv demo``: the built-in synthetic scenes through the whole method, evaluated and drawn."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Sequence

from pedenv.config import Config
from pedenv.io.datasets.memory import MemoryDataset
from pedenv.io.outputs import write_outputs
from pedenv.io.sinks import ExtraOutputs
from pedenv.apps.evaluate import run_evaluation
from pedenv.evaluation.result import EvaluationResult
from pedenv.records import Scene


#: The scene of the demo's animated bird's-eye view (the busiest: 37 people per frame on average).
VIDEO_SCENE = "crowd"


def builtin_scenes(seed: int = 0, count: int | None = None, *, terrain: bool = False,
                   frame_rate_hz: float = 10.0) -> list[Scene]:
    """``count`` built-in scenes (all scenarios once by default; more repeat them with new seeds).

    Scenes beyond the first round are named ``<scenario>-<k>``.
    """
    from pedenv.synthetic import SCENARIOS, generate_scenes

    n = len(SCENARIOS) if count is None else int(count)
    if n < 1:
        raise ValueError(f"the number of scenes must be at least 1, got {n}")
    scenes: list[Scene] = []
    round_ = 0
    while len(scenes) < n:
        names = list(SCENARIOS[: n - len(scenes)])
        batch = generate_scenes(seed + round_, names, terrain=terrain, frame_rate_hz=frame_rate_hz)
        scenes.extend(batch if round_ == 0 else [rename_scene(s, f"{s.name}-{round_}") for s in batch])
        round_ += 1
    return scenes


def rename_scene(scene: Scene, name: str) -> Scene:
    """The same scene under another name (its frames too)."""
    return Scene(name, tuple(replace(f, scene=name) for f in scene.frames), scene.description)


def run_demo(output_dir: str | Path, *, seed: int = 0, config: Config | None = None, terrain: bool = False,
             pose_backend: str = "detector-model", progress: bool = True,
             extra_outputs: ExtraOutputs | None = None) -> EvaluationResult:
    """Generate the built-in scenes, run and evaluate the model, write every output.

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
    return result


def scenes_summary(scenes: Sequence[Scene]) -> str:
    """One line: scenes, frames and labelled pedestrians."""
    frames = sum(len(s) for s in scenes)
    peds = sum(len(f.ground_truth) for s in scenes for f in s.frames if f.ground_truth is not None)
    return f"{len(scenes)} scenes, {frames} frames, {peds} visible pedestrians"
