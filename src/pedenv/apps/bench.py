"""``pedenv bench``: stage timings next to the paper's (Sec. IV-D, RTX 3090 + Threadripper).

Tracking per frame and position per pedestrian are measured on frames with a fixed
number of walking pedestrians in front of a driving ego, through the real model.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pedenv.body import standing_body, world_keypoints
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.geometry import invert_transform, project
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame

if TYPE_CHECKING:
    from rich.table import Table

PAPER_MS = {"tracking_per_frame": 0.35, "position_per_pedestrian": 0.29, "pose_network": 39.94, "total": 40.54}


def bench_frames(n_pedestrians: int, n_frames: int = 100, seed: int = 0, camera: Camera | None = None) -> list[Frame]:
    """Frames at 10 Hz of an ego at 30 km/h with ``n_pedestrians`` walking 5-60 m ahead
    (those a walk has taken behind the camera or out of the image are not detected)."""
    rng = np.random.default_rng(seed)
    camera = camera or Camera.from_fov()
    start = np.column_stack([rng.uniform(8, 60, n_pedestrians), rng.uniform(-12, 12, n_pedestrians)])
    vel = rng.normal(0, 1.0, (n_pedestrians, 2))
    heights = rng.normal(1.72, 0.09, n_pedestrians)
    body, facing_ego = standing_body(heights), np.full(n_pedestrians, np.pi)  # upright, facing -x
    frames = []
    for i in range(n_frames):
        t = 0.1 * i
        ego = EgoPose.from_xy_yaw(8.33 * t, 0.0, 0.0)
        xy = start + vel * t + np.array([8.33 * t, 0.0])
        pts = world_keypoints(np.column_stack([xy, np.zeros(n_pedestrians)]), facing_ego, body)
        frame = Frame(i, t, camera, ego)
        uv, depth = project(pts, camera.intrinsics, invert_transform(frame.cam_to_world))
        uv += rng.normal(0, 1.0, uv.shape)
        # what a camera sees: people wholly in front of it, their box overlapping the image
        seen = (depth > 0.5).all(axis=1) & (uv[..., 0].max(axis=1) > 0) & (uv[..., 0].min(axis=1) < camera.width)
        detections = Detections(uv[seen], np.full((int(seen.sum()), 17), 0.9))
        frames.append(replace(frame, detections=detections))
    return frames


#: Most frames per measurement: the frames are built in memory first (10,000 frames of 100
#: pedestrians are about 50 MB), and 10,000 frames already time a stage to well under 1 %.
MAX_BENCH_FRAMES = 10_000


def bench_core(pedestrian_counts: Iterable[int] = (10, 100), n_frames: int = 100,
               config: Config | None = None) -> list[dict]:
    """Tracking ms/frame and position ms/pedestrian of the model for each pedestrian count.

    ``config``: by default the paper's method (``Config(method="paper")``), whose stages the
    paper timed; pass ``Config()`` to time the fused method.
    """
    if isinstance(n_frames, bool) or not isinstance(n_frames, int) or not 1 <= n_frames <= MAX_BENCH_FRAMES:
        raise InputError(f"the number of frames to time must be an integer in [1, {MAX_BENCH_FRAMES}], "
                         f"got {n_frames!r}")
    rows = []
    for n in pedestrian_counts:
        frames = bench_frames(n, n_frames)
        model = PedestrianEnvironmentModel(config or Config(method="paper"))
        for f in frames[:5]:  # warm-up: imports and caches
            model.update(f)
        model = PedestrianEnvironmentModel(config or Config(method="paper"))
        t0 = time.perf_counter()
        for f in frames:
            model.update(f)
        wall = time.perf_counter() - t0
        ms = model.timer.per_stage_ms()
        rows.append({"pedestrians": n, **ms, "update_per_frame": 1e3 * wall / len(frames)})
        if model.behaviour is not None:  # the behaviour cues' own clock, inside update (fused preset)
            rows[-1]["behaviour_per_frame"] = 1e3 * model.behaviour.elapsed_s / len(frames)
    return rows


def format_behaviour_cost(rows: list[dict]) -> Table:
    """A rich table: ``model.update`` of the fused preset per frame and the behaviour cues' share of it."""
    from rich.table import Table

    table = Table(title="pedenv bench, the fused preset: behaviour cues (orientation, path, conflict) in update")
    for col in ("pedestrians", "update [ms]", "behaviour [ms]", "behaviour / rest of update"):
        table.add_column(col, justify="right")
    for r in rows:
        extra = r.get("behaviour_per_frame", 0.0)
        table.add_row(str(r["pedestrians"]), f"{r['update_per_frame']:.3f}", f"{extra:.3f}",
                      f"{100 * extra / max(r['update_per_frame'] - extra, 1e-9):.1f} %")
    return table


def format_bench(rows: list[dict], pose_rows: list[dict] | None = None) -> Table:
    """A rich table of the rows, with the paper's figures and the speed-up over them."""
    from rich.table import Table

    table = Table(title="pedenv bench, the paper's method (this CPU) vs. the paper (RTX 3090 + Threadripper 3960X)")
    for col in ("stage", "pedestrians", "pedenv [ms]", "paper [ms]", "paper / pedenv"):
        table.add_column(col, justify="left" if col == "stage" else "right")
    for r in rows:
        for key, label in (("tracking_per_frame", "tracking per frame"),
                           ("position_per_pedestrian", "position per pedestrian")):
            table.add_row(label, str(r["pedestrians"]), f"{r[key]:.4f}", f"{PAPER_MS[key]:.2f}",
                          f"{PAPER_MS[key] / r[key]:.1f}x")
        table.add_row("model.update per frame", str(r["pedestrians"]), f"{r['update_per_frame']:.3f}", "", "")
    for r in pose_rows or []:
        paper = PAPER_MS.get(r.get("paper_key", ""))
        table.add_row(r["stage"], str(r.get("pedestrians", "")), f"{r['ms']:.2f}",
                      "" if paper is None else f"{paper:.2f}", "" if paper is None else f"{paper / r['ms']:.2f}x")
    return table


def bench_end_to_end(repeats: int = 10, threads: int = 2, device: str = "auto") -> list[dict]:
    """Pose network + model (the paper's method) per 1600x900 frame, and the networks alone
    (onnx square/rect, ultralytics).

    Rows for :func:`format_bench`: ``stage``, ``ms`` and the paper figure they compare to.
    """
    from pedenv.pose.onnx_backend import OnnxPose
    from pedenv.pose.timing import benchmark_image, benchmark_pose

    rows = []
    for r in benchmark_pose(repeats=repeats, threads=threads, device=device):
        if r.get("ms_per_frame") is not None:
            rows.append({"stage": f"pose network {r['backend']} {r['input_size']}", "ms": r["ms_per_frame"],
                         "pedestrians": r.get("persons", ""), "paper_key": "pose_network",
                         "provider": r.get("provider", "")})
    image = benchmark_image()
    pose = OnnxPose(input_size=(384, 640), threads=threads, device=device)
    model = PedestrianEnvironmentModel(Config(method="paper"))
    camera = Camera.from_fov()
    times = []
    for i in range(repeats + 2):
        start = time.perf_counter()
        frame = Frame(i, 0.1 * i, camera, EgoPose.from_xy_yaw(0.8 * i, 0.0, 0.0), image=image)
        state = model.update(replace(frame, detections=pose(frame)))
        times.append(1e3 * (time.perf_counter() - start))
    rows.append({"stage": "end to end (onnx 384x640 + model)", "ms": float(np.mean(times[2:])),
                 "pedestrians": len(state.pedestrians), "paper_key": "total"})
    return rows


def bench_detection_modes(samples_root: str | Path | None = None, repeats: int = 5, threads: int = 2,
                          device: str = "auto") -> list[dict]:
    """``fast``, ``far`` and ``stream`` side by side: ms and units per 1600x900 frame, recall on the real samples.

    The time is over ``repeats`` runs on a 1600x900 street frame seen by a level camera 1.5 m
    high (the far levels' bands apply); ``stream`` sees it as ``repeats`` consecutive frames at
    10 Hz after a first (cold start, whole band) frame, which is not timed. Recall is measured
    on the samples under ``samples_root`` (KITTI, MOT17 and nuScenes; ``stream`` takes each
    sequence's samples as consecutive frames) when given, else left out. Rows: ``mode``,
    ``ms`` (mean), ``ms_min``, ``passes``, ``units`` (network input pixels in 384x640 passes:
    the cost whatever the load), ``load`` (1-minute load average while timing), ``cpus``,
    ``recall``, ``recall_40_80``, ``recall_80_up``, ``precision``, ``units_samples``.
    """
    import os

    from pedenv.apps.evaluate_detections import evaluate_detections, network_units
    from pedenv.detection import create_detector
    from pedenv.detection.geometry import CameraGeometry
    from pedenv.pose.timing import benchmark_image

    image = benchmark_image()
    geometry = CameraGeometry.level(Camera.from_fov().intrinsics, 1.5)
    rows = []
    for mode in ("fast", "far", "stream"):
        pose: Any = create_detector("onnx", detection=mode, threads=threads, device=device)
        def run(i: int, pose: Any = pose, mode: str = mode) -> None:
            if mode == "stream":
                pose.detect_frame(image, geometry, 0.1 * i)
            else:
                pose.detect(image, geometry)

        run(0)
        times, units = [], []
        for i in range(1, repeats + 1):
            start = time.perf_counter()
            run(i)
            times.append(1e3 * (time.perf_counter() - start))
            units.append(network_units(pose))
        row = {"mode": mode, "ms": float(np.mean(times)), "ms_min": float(np.min(times)),
               "passes": len(pose.last_passes), "units": float(np.mean(units)), "load": os.getloadavg()[0],
               "cpus": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()}
        if samples_root is not None:
            if mode == "stream":
                pose.restart()
            report = evaluate_detections(samples_root, backend=pose, threads=threads)
            block = report["summary"]["all"]
            goals = {b["bin"]: b["recall"] for b in block["by_goal_height"]}
            row.update(recall=block["recall"], recall_40_80=goals["40-80"], recall_80_up=goals[">=80"],
                       precision=block["precision"], units_samples=report["cost"]["all"]["units_per_frame"])
        rows.append(row)
    return rows


def format_detection_modes(rows: list[dict]) -> Table:
    """A rich table of :func:`bench_detection_modes` rows, the modes side by side."""
    from rich.table import Table

    load = ", ".join(f"load {r['load']:.1f} on {r['cpus']} cores" for r in rows[:1])
    table = Table(title="detection modes: one 1600x900 frame (this CPU, " + load + ") and the real samples "
                        "(stream: each sequence's frames in order); units = network input pixels / (384 x 640)")
    for col in ("mode", "passes", "units", "ms / frame", "min ms", "recall", "recall 40-80 px", "recall >= 80 px",
                "precision", "units (samples)"):
        table.add_column(col, justify="left" if col == "mode" else "right")
    pct = lambda x: "-" if x is None else f"{100 * x:.0f} %"  # noqa: E731
    for r in rows:
        units = r.get("units_samples")
        table.add_row(r["mode"], str(r["passes"]), f"{r['units']:.1f}", f"{r['ms']:.0f}", f"{r['ms_min']:.0f}",
                      pct(r.get("recall")), pct(r.get("recall_40_80")), pct(r.get("recall_80_up")),
                      pct(r.get("precision")), "-" if units is None else f"{units:.1f}")
    return table
