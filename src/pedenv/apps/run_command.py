"""``pedenv run``: one recording or a manifest of them, and the rules between the command's flags.

:func:`run_command` is what the command calls with its flags grouped: it refuses the flags
that do not go together (one InputError naming them) and runs
:func:`~pedenv.apps.run.run_recording` or :func:`~pedenv.apps.batch.run_manifest`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions, RecordingSource
from pedenv.errors import InputError

#: The flags that choose a bag's topics and frames, as :class:`~pedenv.recordings.bag_topics.BagOptions` names them.
BAG_FLAGS = ("image_topic", "camera_info_topic", "odometry_topic", "world_frame", "vehicle_frame")


@dataclass(frozen=True)
class RunOutcome:
    """What ``pedenv run`` prints: ``summary`` is ``run.json`` of one recording, or ``summary.json``
    of a ``manifest`` run (then ``summary["failed"]`` counts the failed recordings)."""

    summary: dict
    manifest: bool = False


def run_command(*, source: RecordingSource, output: OutputOptions, flags: OutputFlags, pose: PoseOptions,
                method: MethodOptions, executor: ExecutorOptions, manifest: Path | None = None,
                realtime: bool = False) -> RunOutcome:
    """Run ``source`` (or every recording of ``manifest``) as ``pedenv run`` does, with a progress bar on stderr.

    ``flags``: the per-frame outputs of a single recording (``--parquet``, ``--rerun``, ``--mcap``,
    ``--ros-out``, ``--live``). ``executor``: a manifest's executor (serial or Ray), or ``--resume``.
    ``realtime``: frames at the recording's rate (:class:`~pedenv.apps.pipeline.PipelineConfig`).
    Refused with one InputError: a recording's files beside a manifest, single-recording outputs,
    ``--realtime`` or ``--device`` with a manifest, the executor's flags without one, a bag beside
    the files it holds, the bag's topic flags without a bag, a vehicle recording without its
    calibration and ego poses (a ``static`` one without a calibration has its camera estimated
    from the people it sees: :mod:`pedenv.apps.calibrate`).
    """
    if manifest is not None:
        refuse_beside_manifest(source, flags, paced=realtime or pose.device != "auto")
        from pedenv.apps.output_safety import check_paths

        check_paths([("--manifest", manifest), ("--config", method.config if isinstance(method.config, (str, Path))
                                                 else None)], [], output.folder)
        from pedenv.apps.batch import run_manifest

        summary = run_manifest(manifest, output, pose, executor=executor, config=method.config, method=method.method,
                               progress=True)
        return RunOutcome(summary, manifest=True)
    check_single_recording(source, executor)
    from rich.console import Console

    from pedenv.apps.pipeline import PipelineConfig
    from pedenv.apps.progress import progress_callback
    from pedenv.apps.run import run_recording

    if flags.live is not None:  # the port chosen and printed before the run (run.json gives it too)
        from pedenv.apps.run_outputs import free_port

        flags = dataclasses.replace(flags, live=flags.live or free_port())
    output = dataclasses.replace(output, extra=flags.extra_outputs(output))
    console = Console(stderr=True, soft_wrap=True, emoji=False, markup=False)
    if flags.live is not None:
        console.print(f"live: ws://127.0.0.1:{flags.live} (connect Foxglove to it)", highlight=False)
    with progress_callback("frames", console=console) as progress:
        summary = run_recording(source, output, pose, config=method.config, method=method.method,
                                pipeline=PipelineConfig(realtime=realtime), progress=progress)
    return RunOutcome(summary)


def refuse_beside_manifest(source: RecordingSource, flags: OutputFlags, *, paced: bool) -> None:
    """One error for the flags of single recordings given with ``--manifest``: the recording's
    files and timing, the per-frame outputs, ``--realtime`` and ``--device`` (``paced``), a bag."""
    per_recording = (("--images", source.images), ("--video", source.video), ("--calibration", source.calibration),
                     ("--ego-poses", source.ego_poses), ("--fps", source.fps), ("--start-time", source.start_time),
                     ("--static", source.static or None))
    given = [flag for flag, value in per_recording if value is not None]
    if given:
        raise InputError(f"{', '.join(given)}: with --manifest each row names its recording's files and timing")
    if flags.parquet or flags.rerun or flags.mcap:
        raise InputError("--parquet, --rerun and --mcap are written by single-recording runs, not --manifest runs")
    if paced:
        raise InputError("--realtime and --device apply to single-recording runs, not --manifest runs (which "
                         "take the GPU where onnxruntime has one)")
    if flags.ros is not None or source.bag is not None or flags.live is not None:
        raise InputError("--ros-out, --live and --bag are for single-recording runs, not --manifest runs")


def check_single_recording(source: RecordingSource, executor: ExecutorOptions) -> None:
    """A single recording's flags: a bag alone or the files (calibration and ego poses, or a static
    camera), the bag's topic flags only with a bag, no executor flags."""
    chosen = {name: getattr(source.bag_options, name, None) for name in BAG_FLAGS}
    if source.bag is None:
        given = [f"--{k.replace('_', '-')}" for k, v in chosen.items() if v is not None]
        if given:
            raise InputError(f"{', '.join(given)} apply to --bag")
        if not source.static and source.calibration is None:  # without --ego-poses: pedenv.odometry
            raise InputError("give --calibration (with --ego-poses, or without them a vehicle's ego poses are "
                             "estimated from the images), or --static for a fixed camera (without --calibration "
                             "it is estimated from the people it sees), or a --bag, or a --manifest of recordings")
    elif any(v is not None for v in (source.images, source.video, source.calibration, source.ego_poses)) \
            or source.static:
        raise InputError("--bag holds the images, camera and ego poses: leave out --images, --video, --calibration, "
                         "--ego-poses and --static")
    if executor.name != "serial" or executor.address or executor.workers or executor.resume:
        raise InputError("--executor, --address, --workers and --resume apply to --manifest runs")
