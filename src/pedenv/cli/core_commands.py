"""``pedenv demo | simulate | evaluate | bench``."""

from __future__ import annotations

import sys
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from pedenv.cli.app import app, console, stdout_console
from pedenv.cli.pose_commands import DEVICE
from pedenv.config import Config

if TYPE_CHECKING:
    from pedenv.pose import PoseBackend

#: stdout console for tables and results; wide enough for the tables when piped
_out = stdout_console(None if sys.stdout.isatty() else 140)


def _config(path: Path | None, method: str | None = None, **paper) -> Config:
    """The config of ``--config`` (or the defaults) with the paper settings given and ``method``'s preset."""
    from pedenv.localization import configure

    config = Config.load(path) if path else Config()
    changes = {k: v for k, v in paper.items() if v is not None}
    config = config.replace(paper=changes) if changes else config
    return configure(config, method) if method else config


def _extra_outputs(output: Path, parquet: bool, rerun: Path | None, mcap: Path | None, *,
                   matches: bool = False, video_scene: str | None = None, ros: Path | None = None,
                   overwrite: bool = False):
    """The ExtraOutputs of the ``--parquet``, ``--rerun``, ``--mcap``, ``--ros-out`` flags (and the bird's-eye
    video)."""
    from pedenv.outputs.sinks import ExtraOutputs

    return ExtraOutputs(parquet=output / "environment.parquet" if parquet else None,
                        matches_parquet=output / "matches.parquet" if parquet and matches else None,
                        rerun=rerun, mcap=mcap, ros=ros,
                        birds_eye_video=output / "birds_eye.mp4" if video_scene else None, birds_eye_scene=video_scene,
                        overwrite=overwrite)


#: The flags of the per-frame outputs, shared by demo and evaluate (run has them too).
_PARQUET = typer.Option(
    False, "--parquet", help="Also write environment.parquet (and matches.parquet when evaluating)."
)
_RERUN = typer.Option(None, "--rerun", help="Write a Rerun recording (FILE.rrd; one file per scene when several; "
                                             "an existing file only with --overwrite).")
_MCAP = typer.Option(None, "--mcap",
                     help="Write a Foxglove MCAP file (FILE.mcap; an existing file only with --overwrite).")
_ROS_OUT = typer.Option(None, "--ros-out", help="Write ROS 2 messages as a rosbag2 FILE.mcap (FILE-<method>.mcap "
                                                 "with --method both).")
_OVERWRITE = typer.Option(False, "--overwrite", help="Replace the outputs of an earlier run in --output, and "
                                                     "an existing --rerun/--mcap/--ros-out file.")
_EXECUTOR = typer.Option("serial", "--executor", help="serial (in this process) or ray (one task per scene).")
_ADDRESS = typer.Option(None, "--address", help="Ray cluster HOST:PORT (`ray start --head`); default: a local Ray.")
_WORKERS = typer.Option(None, "--workers", help="Ray: CPUs of the local Ray, or most tasks at once on a cluster.")
_RESUME = typer.Option(False, "--resume", help="Keep the scenes an earlier run in --output completed; run the rest.")


def _print_result(metrics, title: str = "") -> None:
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
    config: Path | None = typer.Option(None, "--config", help="A config.json to use instead of the defaults."),
    method: str | None = typer.Option(
        None, "--method", help="Method of the outputs: fused (default, or the --config file's) or paper; "
                               "the other one runs beside it on the same frames for the table."),
    overwrite: bool = _OVERWRITE,
    parquet: bool = _PARQUET,
    rerun: Path | None = _RERUN,
    mcap: Path | None = _MCAP,
    ros_out: Path | None = _ROS_OUT,
) -> None:
    """Run the paper's and the fused method on the built-in synthetic scenes; print them side by side, write plots."""
    from pedenv.apps.compare import comparison_by_scene_table, comparison_summary_table
    from pedenv.apps.demo import VIDEO_SCENE, run_demo
    from pedenv.outputs.output_dir import prepare_output_dir

    cfg = _config(config, method)
    extra = _extra_outputs(output, parquet, rerun, mcap, matches=True, video_scene=VIDEO_SCENE, ros=ros_out,
                           overwrite=overwrite)
    extra.check()
    prepare_output_dir(output, overwrite=overwrite, command="pedenv demo")
    result = run_demo(output, seed=seed, config=cfg, terrain=terrain, pose_backend=pose_backend, extra_outputs=extra)
    methods = result.extras["methods"]
    _out.print(comparison_by_scene_table(methods, "pedenv demo: built-in synthetic scenes, the same frames and "
                                                  f"{result.metrics.info['pose_backend']} skeletons"))
    _out.print(comparison_summary_table(methods))
    _out.print(f"outputs below: method {cfg.method}", highlight=False)
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
    from pedenv.apps.demo import SceneCounter, iter_builtin_scenes
    from pedenv.datasets import scene_writer
    from pedenv.outputs.output_dir import prepare_output_dir

    write = scene_writer(fmt)
    rate = frame_rate if frame_rate is not None else (12.0 if fmt == "nuscenes" else 10.0)
    stream = iter_builtin_scenes(seed, scenes, terrain=terrain, frame_rate_hz=rate)
    prepare_output_dir(output, overwrite=overwrite, command="pedenv simulate")
    counter = SceneCounter()
    write((counter.add(scene) for scene in stream), output)
    _out.print(f"wrote {counter.summary()} as {fmt} to {output}", highlight=False)


@app.command()
def evaluate(
    dataset: str = typer.Option(..., "--dataset", help="synthetic, nuscenes or carla."),
    data_root: Path = typer.Option(..., "--data-root", help="The dataset's root folder."),
    output: Path = typer.Option(..., "--output", help="Folder for metrics, JSON Lines and plots."),
    scenes: str | None = typer.Option(None, "--scenes", help="Comma-separated scene names (default: all)."),
    version: str = typer.Option("v1.0-mini", "--version", help="nuScenes version folder."),
    pose_backend: str | None = typer.Option(None, "--pose-backend", help="Default: the dataset's own."),
    config: Path | None = typer.Option(None, "--config", help="A config.json to use instead of the defaults."),
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
    overwrite: bool = _OVERWRITE,
    detection: str | None = typer.Option(None, "--detection", help="onnx backend: far, stream or fast (default: far)."),
    parquet: bool = _PARQUET,
    rerun: Path | None = _RERUN,
    mcap: Path | None = _MCAP,
    ros_out: Path | None = _ROS_OUT,
    executor: str = _EXECUTOR,
    address: str | None = _ADDRESS,
    workers: int | None = _WORKERS,
    resume: bool = _RESUME,
    device: str = DEVICE,
) -> None:
    """Evaluate the environment model on a dataset with the paper's protocol."""
    from pedenv.apps.evaluate import evaluate_dataset
    from pedenv.datasets import open_dataset
    from pedenv.errors import InputError

    options = {"version": version} if dataset == "nuscenes" else {}
    data = open_dataset(dataset, data_root, **options)
    names = [s.strip() for s in scenes.split(",") if s.strip()] if scenes else None
    cfg = _config(config, method if method != "both" else None, refine=False if no_refinement else None,
                  initial_estimate=initial_estimate)
    if (no_refinement or initial_estimate) and method != "both" and cfg.method != "paper":
        raise InputError(f"--no-refinement and --initial-estimate change the paper's method, not {cfg.method}; "
                         "add --method paper")
    if cues:
        cfg = cfg.replace(fused={"cues": tuple(c.strip() for c in cues.split(",") if c.strip())})
    onnx = None  # the onnx backend's factory: called here, or once per Ray worker
    if detection is not None or pose_backend == "onnx" or device != "auto":
        from pedenv.pose.base import create_pose_backend

        if (pose_backend or data.default_pose_backend) != "onnx":
            raise InputError("--detection and --device apply to the onnx pose backend; add --pose-backend onnx")
        threshold = {} if cfg.tracking.pose_score_threshold is None else {
            "score_threshold": cfg.tracking.pose_score_threshold}
        cfg = cfg.replace(detection={"mode": detection or "far"})  # saved in config.json with the merge
        onnx = partial(create_pose_backend, "onnx", detection=cfg.detection, merge=cfg.merge, device=device,
                       **threshold)
    if executor == "serial" and (address is not None or workers is not None):
        from pedenv.errors import InputError

        raise InputError("--address and --workers apply to --executor ray")
    if executor != "serial" or resume:
        _evaluate_distributed(data, executor=executor, address=address, workers=workers, scenes=names, config=cfg,
                              pose_backend=onnx or pose_backend, output=output, resume=resume, overwrite=overwrite,
                              refused={"--method both": method == "both", "--ablation": ablation, "--parquet": parquet,
                                       "--rerun": rerun is not None, "--mcap": mcap is not None,
                                       "--ros-out": ros_out is not None})
        return
    backend: str | PoseBackend | None = onnx() if onnx else pose_backend
    from pedenv.outputs.output_dir import prepare_output_dir

    extra = _extra_outputs(output, parquet, rerun, mcap, matches=True, ros=ros_out, overwrite=overwrite)
    extra.check()
    prepare_output_dir(output, overwrite=overwrite, command="pedenv evaluate")
    if method == "both":
        from pedenv.apps.compare import (
            compare_methods,
            comparison_by_scene_table,
            comparison_summary_table,
            outputs_per_method,
        )

        methods = ("paper", "fused")
        results = compare_methods(data, methods=methods, scenes=names, config=cfg, pose_backend=backend,
                                  output_dir=output, progress=True,
                                  extra_outputs=outputs_per_method(extra, methods, output))
        _out.print(comparison_by_scene_table(results))
        _out.print(comparison_summary_table(results))
    else:
        metrics = evaluate_dataset(data, scenes=names, config=cfg, pose_backend=backend, output_dir=output,
                                   progress=True, extra_outputs=extra)
        _print_result(metrics, f"{dataset}: {metrics.info['pose_backend']} skeletons, method {metrics.info['method']}")
    if ablation:
        from pedenv.apps.ablation import run_ablation

        _out.print(run_ablation(data, scenes=names, config=cfg, pose_backend=backend, output_dir=output))
    _out.print(f"outputs: {output}", highlight=False)


def _evaluate_distributed(data, *, output: Path, resume: bool, overwrite: bool, refused: dict[str, bool],
                          **options) -> None:
    """``pedenv evaluate --executor ray`` or ``--resume``: one task per scene; failed scenes are listed, exit code 1."""
    from pedenv.apps.distributed import evaluate_distributed
    from pedenv.errors import InputError

    given = [flag for flag, on in refused.items() if on]
    if given:
        raise InputError(f"{', '.join(given)} run in the serial in-process evaluation only; leave out --executor ray "
                         f"and --resume")
    result = evaluate_distributed(data, output_dir=output, resume=resume, overwrite=overwrite, progress=True, **options)
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
        Path("../shared/samples/real"),
        "--samples",
        help="Real samples for the detection modes' recall (skipped if absent).",
    ),
    device: str = DEVICE,
) -> None:
    """Time the stages next to the paper's figures (tracking, position, pose network, end to end)."""
    from pedenv.apps.bench import bench_core, format_bench
    from pedenv.errors import InputError

    rows = bench_core(n_frames=frames)
    pose_rows = []
    if pose:
        from pedenv.apps.bench import bench_end_to_end

        try:
            pose_rows = bench_end_to_end(device=device)
        except (ImportError, InputError) as exc:
            console.print(f"pose networks not timed: {exc}", highlight=False, markup=False)
    _out.print(format_bench(rows, pose_rows))
    providers = sorted({r["provider"] for r in pose_rows if r.get("provider")})
    if providers:
        _out.print(f"pose networks ran on: {', '.join(providers)} (--device {device})", highlight=False)
    from pedenv.apps.bench import format_behaviour_cost
    from pedenv.config import Config

    _out.print(format_behaviour_cost(bench_core(n_frames=frames, config=Config())))
    if pose and pose_rows:
        from pedenv.apps.bench import bench_detection_modes, format_detection_modes

        root = samples if samples is not None and samples.is_dir() else None
        _out.print(format_detection_modes(bench_detection_modes(root, device=device)))
