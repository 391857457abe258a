"""``pedenv bench``: the stage timings, the behaviour cues' cost and the detection modes, table by table.

:func:`bench_tables` is what the command calls; it yields each table as soon as it is measured
(a run takes minutes), so the command prints them one by one.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pedenv.errors import InputError


@dataclass(frozen=True)
class BenchOutput:
    """One thing to print: a rich table or a line; ``note``: a line for stderr (what was not measured)."""

    item: Any
    note: bool = False


def bench_tables(*, frames: int = 100, pose: bool = True, samples: Path | None = None,
                 device: str = "auto") -> Iterator[BenchOutput]:
    """The tables of ``pedenv bench``: tracking and position over ``frames`` frames beside the
    paper's figures (with the pose networks end to end when ``pose`` and the models are prepared;
    else a note why not), the devices they ran on, the behaviour cues' cost, and the detection
    modes (recall on ``samples``, a folder of the real samples, when it is one; else left out)."""
    from pedenv.apps.bench import bench_core, format_behaviour_cost, format_bench
    from pedenv.config import Config

    rows = bench_core(n_frames=frames)
    pose_rows: list[dict] = []
    if pose:
        from pedenv.apps.bench import bench_end_to_end

        try:
            pose_rows = bench_end_to_end(device=device)
        except (ImportError, InputError) as exc:
            yield BenchOutput(f"pose networks not timed: {exc}", note=True)
    yield BenchOutput(format_bench(rows, pose_rows))
    providers = sorted({r["provider"] for r in pose_rows if r.get("provider")})
    if providers:
        yield BenchOutput(f"pose networks ran on: {', '.join(providers)} (--device {device})")
    yield BenchOutput(format_behaviour_cost(bench_core(n_frames=frames, config=Config())))
    if pose and pose_rows:
        from pedenv.apps.bench import bench_detection_modes, format_detection_modes

        root = samples if samples is not None and samples.is_dir() else None
        yield BenchOutput(format_detection_modes(bench_detection_modes(root, device=device)))
