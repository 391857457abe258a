"""``pedenv demo | simulate | evaluate | bench``: each parses its flags, calls one application function, prints."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from pedenv.cli.app import app, console, stdout_console
from pedenv.cli.options import (
    Address,
    ConfigFile,
    Detection,
    Device,
    Executor,
    Mcap,
    ObjectStore,
    Overwrite,
    Parquet,
    RerunOption,
    Resume,
    RosOut,
    Workers,
    split_names,
)
from pedenv.datasets import DATASETS

if TYPE_CHECKING:
    from pedenv.apps.evaluate_command import EvaluateOutcome
    from pedenv.evaluation.metrics import Metrics
    from pedenv.evaluation.result import EvaluationResult

#: stdout console for tables and results; wide enough for the tables when piped
_out = stdout_console(None if sys.stdout.isatty() else 140)


def _print_result(metrics: Metrics, title: str = "") -> None:
    from pedenv.evaluation.report import results_table, summary_lines

    _out.print(results_table(metrics, title))
    for line in summary_lines(metrics):
        _out.print(line, highlight=False)


@app.command()
def demo(
    output: Path = typer.Option(Path("output/demo"), "--output", help="Folder for metrics, JSON Lines and plots."),
    seed: int = typer.Option(0, "--seed", help="Seed of the built-in scenes and the detector model."),
    terrain: bool = typer.Option(False, "--terrain/--flat", help="Rolling terrain and vehicle pitch, or a flat world."),
    pose_backend: str = typer.Option("detector-model", "--pose-backend", help="detector-model or ground-truth."),
    config: ConfigFile = None,
    method: str | None = typer.Option(
        None, "--method", help="Method of the outputs: fused (default, or the --config file's) or paper; "
                               "the other one runs beside it on the same frames for the table."),
    overwrite: Overwrite = False,
    parquet: Parquet = False,
    rerun: RerunOption = None,
    mcap: Mcap = None,
    ros_out: RosOut = None,
) -> None:
    """Run the paper's and the fused method on the built-in synthetic scenes; print them side by side, write plots."""
    from pedenv.apps.compare import comparison_by_scene_table, comparison_summary_table
    from pedenv.apps.demo import demo_command
    from pedenv.apps.options import MethodOptions, OutputFlags, OutputOptions

    result = demo_command(output=OutputOptions(output, overwrite=overwrite),
                          flags=OutputFlags(parquet=parquet, rerun=rerun, mcap=mcap, ros=ros_out),
                          method=MethodOptions(config, method), seed=seed, terrain=terrain, pose_backend=pose_backend)
    methods = result.extras["methods"]
    _out.print(comparison_by_scene_table(methods, "pedenv demo: built-in synthetic scenes, the same frames and "
                                                  f"{result.metrics.info['pose_backend']} skeletons"))
    _out.print(comparison_summary_table(methods))
    _out.print(f"outputs below: method {result.metrics.info['method']}", highlight=False)
    for name, path in result.extras["paths"].items():
        _out.print(f"{name}: {path}", highlight=False)
    _out.print(f"environment: {output / 'environment.jsonl'}", highlight=False)
    for path in result.extras.get("files", []):
        _out.print(f"{path.suffix[1:]}: {path}", highlight=False)


@app.command()
def simulate(
    output: Path = typer.Option(..., "--output", help="Folder to write the scenes to."),
    scenes: int | None = typer.Option(None, "--scenes", help="Number of scenes (default: every scenario once)."),
    seed: int = typer.Option(0, "--seed"),
    fmt: str = typer.Option("synthetic", "--format", help="synthetic, nuscenes or carla."),
    terrain: bool = typer.Option(False, "--terrain/--flat"),
    frame_rate: float | None = typer.Option(None, "--frame-rate", help="Hz; default 10 (12 for nuscenes)."),
    overwrite: bool = typer.Option(False, "--overwrite", help="Replace the outputs of an earlier run in --output."),
) -> None:
    """Write the built-in synthetic scenes to disk in one of the supported formats, each as it is made."""
    from pedenv.apps.demo import simulate_command
    from pedenv.apps.options import OutputOptions

    counter = simulate_command(output=OutputOptions(output, overwrite=overwrite), scenes=scenes, seed=seed, fmt=fmt,
                               terrain=terrain, frame_rate=frame_rate)
    _out.print(f"wrote {counter.summary()} as {fmt} to {output}", highlight=False)


@app.command()
def evaluate(
    dataset: str = typer.Option(..., "--dataset", help=f"{', '.join(DATASETS)}."),
    data_root: Path = typer.Option(..., "--data-root", help="The dataset's root folder."),
    output: Path = typer.Option(..., "--output", help="Folder for metrics, JSON Lines and plots."),
    scenes: str | None = typer.Option(None, "--scenes", help="Comma-separated scene names (default: all)."),
    version: str = typer.Option("v1.0-mini", "--version", help="nuScenes version folder."),
    pose_backend: str | None = typer.Option(None, "--pose-backend", help="Default: the dataset's own."),
    config: ConfigFile = None,
    no_refinement: bool = typer.Option(
        False, "--no-refinement", help="Ablation of the paper method: skip the height refinement."),
    initial_estimate: str | None = typer.Option(
        None, "--initial-estimate", help="Paper method: all-keypoints or midpoint."),
    ablation: bool = typer.Option(
        False, "--ablation", help="Also run the paper method's ablations (whatever --method) and print their table."),
    method: str | None = typer.Option(
        None, "--method", help="fused (default, or the --config file's), paper (the paper's figures), or both: "
                               "side by side on the same frames, each method's outputs in OUTPUT/<method>/ "
                               "(its --parquet tables there too) and FILE-<method>.rrd / .mcap."),
    cues: str | None = typer.Option(None, "--cues", help="fused cues, e.g. ground,triangulation,height."),
    overwrite: Overwrite = False,
    detection: Detection = None,
    parquet: Parquet = False,
    rerun: RerunOption = None,
    mcap: Mcap = None,
    ros_out: RosOut = None,
    executor: Executor = "serial",
    address: Address = None,
    workers: Workers = None,
    object_store_memory: ObjectStore = None,
    resume: Resume = False,
    device: Device = "auto",
) -> None:
    """Evaluate the environment model on a dataset with the paper's protocol."""
    from pedenv.apps.evaluate_command import DatasetChoice, evaluate_command
    from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions

    outcome = evaluate_command(
        dataset=DatasetChoice(dataset, data_root, version=version, scenes=split_names(scenes)),
        output=OutputOptions(output, overwrite=overwrite),
        flags=OutputFlags(parquet=parquet, rerun=rerun, mcap=mcap, ros=ros_out),
        pose=PoseOptions(pose_backend, detection=detection, device=device),
        method=MethodOptions(config, method, refine=False if no_refinement else None,
                             initial_estimate=initial_estimate, cues=split_names(cues)),
        executor=ExecutorOptions(executor, address=address, workers=workers, resume=resume,
                                 object_store_memory=object_store_memory),
        ablation=ablation)
    _print_evaluation(outcome, dataset)


def _print_evaluation(outcome: EvaluateOutcome, dataset: str) -> None:
    """The tables of ``pedenv evaluate``; failed scenes of a run as tasks: one error line each, exit code 1."""
    from pedenv.apps.compare import comparison_by_scene_table, comparison_summary_table

    if outcome.distributed is not None:
        _print_tasks(outcome.distributed, outcome.output)
        return
    if outcome.methods:
        _out.print(comparison_by_scene_table(outcome.methods))
        _out.print(comparison_summary_table(outcome.methods))
    else:
        assert outcome.metrics is not None  # one method: its metrics are set
        info = outcome.metrics.info
        _print_result(outcome.metrics, f"{dataset}: {info['pose_backend']} skeletons, method {info['method']}")
    if outcome.ablation is not None:
        _out.print(outcome.ablation)
    infos = [r.metrics.info for r in outcome.methods.values()] + ([outcome.metrics.info] if outcome.metrics else [])
    if infos and infos[0].get("perception"):
        _out.print(f"figures: {infos[0]['perception']}", highlight=False)
    _out.print(f"outputs: {outcome.output}", highlight=False)


def _print_tasks(result: EvaluationResult, output: Path) -> None:
    """``pedenv evaluate --executor ray`` or ``--resume``: the table; failed scenes are listed, exit code 1."""
    info = result.metrics.info
    _print_result(result.metrics, f"{info['dataset']}: {info['pose_backend']} skeletons, method {info['method']}")
    if result.extras["resumed"]:
        _out.print(f"resumed: {len(result.extras['resumed'])} scene(s) taken from {output}", highlight=False)
    _out.print(f"outputs: {output}", highlight=False)
    for name, exc in result.extras["failures"].items():
        console.print(f"error: scene {name} failed: {exc}", style="red", highlight=False, markup=False)
    if result.extras["failures"]:
        console.print(f"{len(result.extras['failures'])} scene(s) failed; the others are in {output} (re-run with "
                      f"--resume to run only the failed ones)", highlight=False, markup=False)
        raise typer.Exit(1)


@app.command()
def bench(
    frames: int = typer.Option(100, "--frames", help="Frames per measurement."),
    pose: bool = typer.Option(
        True, "--pose/--no-pose", help="Also time the pose networks (needs the prepared models)."
    ),
    samples: Path | None = typer.Option(
        None, "--samples", help="Folder of real samples (kitti/, mot17/, nuscenes-0061/; e.g. ../shared/samples/real) "
                                "for the detection modes' recall (default: none, recall not measured)."),
    device: Device = "auto",
) -> None:
    """Time the stages next to the paper's figures (tracking, position, pose network, end to end)."""
    from pedenv.apps.bench_command import bench_tables

    for output in bench_tables(frames=frames, pose=pose, samples=samples, device=device):
        if output.note:
            console.print(output.item, highlight=False, markup=False)
        else:
            _out.print(output.item, highlight=False)
