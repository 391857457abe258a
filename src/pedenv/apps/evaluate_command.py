"""``pedenv evaluate``: a dataset through one method, both, or the ablations, in this process or as tasks.

:func:`evaluate_command` is what the command calls with its flags grouped: it refuses the
flags that do not go together (one InputError naming them), runs the evaluation and returns
what the command prints (:class:`EvaluateOutcome`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path
from typing import Any

from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions
from pedenv.apps.output_safety import check_outputs, list_files, outside_files, prepare_folder
from pedenv.config import Config
from pedenv.datasets import Dataset, open_dataset
from pedenv.errors import InputError
from pedenv.evaluation.metrics import Metrics
from pedenv.evaluation.result import EvaluationResult
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.pose import PoseBackend


@dataclass(frozen=True)
class DatasetChoice:
    """``--dataset``, ``--data-root``, ``--version`` (nuScenes only) and ``--scenes`` (None: the dataset's defaults)."""

    name: str
    root: str | Path
    version: str = "v1.0-mini"
    scenes: tuple[str, ...] | None = None

    def open(self) -> Dataset:
        options = {"version": self.version} if self.name == "nuscenes" else {}
        return open_dataset(self.name, self.root, **options)


@dataclass
class EvaluateOutcome:
    """What ``pedenv evaluate`` prints.

    metrics: the one method's metrics (None with ``--method both``). methods: method -> its
    EvaluationResult with ``--method both``. distributed: the merged result of a run as tasks
    (``--executor ray`` or ``--resume``; its ``extras`` name the failed and resumed scenes).
    ablation: the ablations' table with ``--ablation``.
    """

    output: Path
    metrics: Metrics | None = None
    methods: dict[str, EvaluationResult] = field(default_factory=dict)
    distributed: EvaluationResult | None = None
    ablation: Any = None


def evaluate_command(*, dataset: DatasetChoice, output: OutputOptions, flags: OutputFlags, pose: PoseOptions,
                     method: MethodOptions, executor: ExecutorOptions, ablation: bool = False) -> EvaluateOutcome:
    """Evaluate ``dataset`` with the paper's protocol into ``output.folder``, as ``pedenv evaluate`` does.

    ``method.method``: ``fused``, ``paper`` or ``both`` (side by side on the same frames, each
    method's outputs in ``<output>/<method>/``). ``ablation``: also the paper method's ablations.
    ``executor``: ``ray`` or ``resume`` run one task per scene (:mod:`pedenv.apps.distributed`).
    Refused with one InputError: ``--no-refinement``/``--initial-estimate`` beside another method
    than the paper's, ``--detection``/``--device`` beside another backend than onnx,
    ``--address``/``--workers`` with the serial executor, and ``--method both``, ``--ablation``
    and the per-frame outputs with tasks.
    """
    data = dataset.open()
    if pose.backend == "onnx" and hasattr(data, "with_images_only"):
        data = data.with_images_only()  # whole drives: the real network where a frame has its image
    cfg = method.load(allow_both=True)
    cfg, backend = onnx_backend(data, cfg, pose)
    executor.check_serial()
    folder = Path(output.folder)
    inputs = [("--data-root", dataset.root), ("--config", method.config if isinstance(method.config, (str, Path))
                                              else None)]
    if executor.name != "serial" or executor.resume:
        refuse_with_tasks(method, flags, ablation=ablation)
        from pedenv.apps.distributed import evaluate_distributed

        check_outputs(folder, inputs, None)

        result = evaluate_distributed(data, executor=executor, scenes=dataset.scenes, config=cfg,
                                      pose_backend=backend or pose.backend, output_dir=folder,
                                      overwrite=output.overwrite, progress=True)
        return EvaluateOutcome(folder, distributed=result)
    extra = flags.extra_outputs(output, matches=True)
    extra.check()
    made = backend() if backend else pose.backend
    prepare_folder(folder, inputs, extra, overwrite=output.overwrite, command="pedenv evaluate")
    try:
        with outside_files(folder, extra) as extra:  # earlier files outside the folder replaced at the end
            outcome = _evaluate_serial(data, dataset.scenes, cfg, made, folder=folder, extra=extra,
                                       both=method.method == "both")
        if ablation:
            from pedenv.apps.ablation import run_ablation

            outcome.ablation = run_ablation(data, scenes=dataset.scenes, config=cfg, pose_backend=made,
                                            output_dir=folder)
    finally:
        list_files(folder, "pedenv evaluate")  # what a later --overwrite may delete
    return outcome


def onnx_backend(data: Dataset, cfg: Config, pose: PoseOptions) -> tuple[Config, Callable[[], PoseBackend] | None]:
    """``cfg`` with ``detection.mode`` set (saved in config.json with the merge) and the onnx backend's
    factory (called here, or once per Ray worker) when ``--detection``, ``--device`` or
    ``--pose-backend onnx`` is given; else ``cfg`` and None. ``--detection`` and ``--device`` need onnx."""
    if pose.detection is None and pose.backend != "onnx" and pose.device == "auto":
        return cfg, None
    from pedenv.detection import create_detector

    if (pose.backend or data.default_pose_backend) != "onnx":
        raise InputError("--detection and --device apply to the onnx pose backend; add --pose-backend onnx")
    threshold = {} if cfg.tracking.pose_score_threshold is None else {
        "score_threshold": cfg.tracking.pose_score_threshold}
    cfg = cfg.replace(detection={"mode": pose.detection or "far"})
    return cfg, partial(create_detector, "onnx", detection=cfg.detection, redetect=cfg.redetect,
                        device=pose.device, **threshold)


def refuse_with_tasks(method: MethodOptions, flags: OutputFlags, *, ablation: bool) -> None:
    """``--method both``, ``--ablation`` and the per-frame outputs run in the serial in-process evaluation only."""
    refused = {"--method both": method.method == "both", "--ablation": ablation, "--parquet": flags.parquet,
               "--rerun": flags.rerun is not None, "--mcap": flags.mcap is not None,
               "--ros-out": flags.ros is not None}
    given = [flag for flag, on in refused.items() if on]
    if given:
        raise InputError(f"{', '.join(given)} run in the serial in-process evaluation only; leave out --executor ray "
                         f"and --resume")


def _evaluate_serial(data: Dataset, scenes: tuple[str, ...] | None, cfg: Config, backend: str | PoseBackend | None,
                     *, folder: Path, extra: ExtraOutputs, both: bool) -> EvaluateOutcome:
    """The evaluation in this process into the prepared ``folder``: one method (its metrics) or both
    (each method's result)."""
    from pedenv.apps.evaluate import evaluate_dataset

    if not both:
        metrics = evaluate_dataset(data, scenes=scenes, config=cfg, pose_backend=backend, output_dir=folder,
                                   progress=True, extra_outputs=extra)
        return EvaluateOutcome(folder, metrics=metrics)
    from pedenv.apps.compare import compare_methods, outputs_per_method

    methods = ("paper", "fused")
    per_method = outputs_per_method(extra, methods, folder)
    results = compare_methods(data, methods=methods, scenes=scenes, config=cfg, pose_backend=backend,
                              output_dir=folder, progress=True, extra_outputs=per_method)
    return EvaluateOutcome(folder, methods=results)
