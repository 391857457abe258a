"""``pedenv run`` end to end against the network's own time, on a real video.

    PYTHONPATH=src python benchmarks/run_pipeline.py --video vtest.avi [--frames 100] [--size 900x1600]
        [--detection fast] [--video-out] [--png-compression fast,none] [--nice 0,10] [--rounds 3]
        [--threads 2] [--side-by-side on,off] [--realtime] [--output-json FILE]

The video (``--video``; the figures of docs/speed.md use ``vtest.avi``, the 768x576 street video
in ``examples/data`` of Debian's ``opencv-doc`` package) is cut to its first ``--frames`` frames,
optionally scaled and centre-cropped to ``--size`` (e.g. 1600x900, nuScenes' camera), and
written as a recording (MJPG video, a GUESSED static camera 5 m up looking 30 deg down, a
standing ego) into a temporary folder. Then, with one pose backend (``--detection``, made
before the clock starts):

1. ``network alone``: every frame read, detected and given to the model (the default, fused
   preset, whose re-detection crops run the network too), nothing written;
2. ``run``: :func:`pedenv.apps.run.run_recording` (what ``pedenv run`` calls, overlays on: a
   PNG per frame, or ``--video-out``), wall time from the call to its return; once per
   ``--png-compression`` and ``--nice`` value given (comma-separated: the variants run one after
   the other, so that they see the same load);
3. with ``--realtime``: the run once more at the recording's own rate: frames done and dropped.

``--side-by-side on,off`` makes one backend each way (``SessionConfig.side_by_side``: the
independent passes of a frame side by side on one-thread sessions, or one after another) and
runs 1 and 2 with each in turn. ``--rounds`` repeats 1 and 2 and prints each variant's median
run; the ratios of a round use that round's network alone. On a shared machine compare variants within one invocation.

The network's time is the backend's session runs (``infer`` wrapped here, so the same
script times main's serial loop: ``PYTHONPATH=/path/to/main/src``); ``ratio`` is run ms per
frame over the network's ms per frame in the same run, and over the network-alone ms per frame.
Timings depend on the load: it is printed (1-minute load average before and after).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np
import yaml


def write_recording(video: Path, out: Path, frames: int, size: tuple[int, int] | None) -> dict:
    """The first ``frames`` frames of ``video`` (scaled and centre-cropped to ``size`` (height,
    width) when given) as a recording in ``out``: its RecordingSource fields (:mod:`pedenv.apps.options`)."""
    cap = cv2.VideoCapture(str(video))
    if not cap.isOpened():
        raise SystemExit(f"{video}: cannot open the video (apt-get install opencv-doc, or give --video)")
    rate = cap.get(cv2.CAP_PROP_FPS) or 10.0
    writer, shape = None, None
    for _ in range(frames):
        ok, bgr = cap.read()
        if not ok:
            break
        if size is not None:
            scale = max(size[0] / bgr.shape[0], size[1] / bgr.shape[1])
            bgr = cv2.resize(bgr, (math.ceil(bgr.shape[1] * scale), math.ceil(bgr.shape[0] * scale)))
            y, x = (bgr.shape[0] - size[0]) // 2, (bgr.shape[1] - size[1]) // 2
            bgr = np.ascontiguousarray(bgr[y:y + size[0], x:x + size[1]])
        if writer is None:
            shape = bgr.shape
            writer = cv2.VideoWriter(str(out / "video.avi"), cv2.VideoWriter.fourcc(*"MJPG"), rate,
                                     (shape[1], shape[0]))
        writer.write(bgr)
    cap.release()
    if writer is None or shape is None:
        raise SystemExit(f"{video}: no readable frame")
    writer.release()
    h, w = shape[:2]
    a = math.radians(30.0)  # GUESSED: 30 deg down, 5 m up, focal = image width
    rotation = [[0.0, -math.sin(a), math.cos(a)], [-1.0, 0.0, 0.0], [0.0, -math.cos(a), -math.sin(a)]]
    (out / "calibration.yaml").write_text("# GUESSED camera\n" + yaml.safe_dump(
        {"width": w, "height": h, "fx": float(w), "fy": float(w), "cx": w / 2, "cy": h / 2,
         "cam_to_vehicle": {"rotation": rotation, "translation": [0.0, 0.0, 5.0]}}))
    (out / "ego_poses.csv").write_text("timestamp,x,y,yaw\n0,0,0,0\n100000,0,0,0\n")
    return {"video": out / "video.avi", "calibration": out / "calibration.yaml", "ego_poses": out / "ego_poses.csv"}


class NetworkClock:
    """A backend's network seconds and session runs since :meth:`reset` (``OnnxPose.network_s``
    and ``network_runs``: passes run side by side count once, as the group's wall time)."""

    def __init__(self, backend) -> None:
        self.backend = backend if hasattr(backend, "infer") else backend.network  # a Detector: its OnnxPose
        self.reset()

    def reset(self) -> None:
        self._start = (self.backend.network_s, self.backend.network_runs)

    @property
    def seconds(self) -> float:
        return self.backend.network_s - self._start[0]

    @property
    def runs(self) -> int:
        return self.backend.network_runs - self._start[1]


def network_alone(rec: dict, backend, clock: NetworkClock) -> dict:
    """Every frame of ``rec`` read, detected and given to the model (the fused preset's
    tracks predicted and passed to the detector, as :class:`pedenv.Pipeline` does),
    nothing written: ms per frame, the network's ms per frame, CPU ms per frame (all threads)."""
    from dataclasses import replace

    from pedenv.config import Config
    from pedenv.model import PedestrianEnvironmentModel
    from pedenv.recordings.footage import load_recording

    cfg = Config()
    clock.reset()
    frames, model = 0, PedestrianEnvironmentModel(cfg)
    start, cpu = time.perf_counter(), time.process_time()
    for frame in load_recording(**rec).frames():
        model.update(replace(frame, detections=backend(frame, model.predict_tracks(frame))))
        frames += 1
    return {"frames": frames, "ms_per_frame": 1e3 * (time.perf_counter() - start) / frames,
            "network_ms_per_frame": 1e3 * clock.seconds / frames,
            "cpu_ms_per_frame": 1e3 * (time.process_time() - cpu) / frames}


def run_once(rec: dict, backend, clock: NetworkClock, folder: Path, variant: dict) -> dict:
    """:func:`~pedenv.apps.run.run_recording` on ``rec`` into ``folder`` (deleted first) with
    ``variant``: ``detection``, ``video_out``, ``realtime`` and, this checkout's pedenv only,
    ``png_compression`` and ``nice`` (None: the defaults)."""
    import shutil

    from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource
    from pedenv.apps.pipeline import PipelineConfig
    from pedenv.apps.run import run_recording

    shutil.rmtree(folder, ignore_errors=True)
    output = {"video_out": variant["video_out"]}
    if variant.get("png_compression"):  # PNG overlays at that compression (the default overlays are JPEG)
        output.update(overlays="png", png_compression=variant["png_compression"])
    pipe = {"realtime": True} if variant.get("realtime") else {}
    if variant.get("nice") is not None:
        pipe["nice"] = variant["nice"]
    clock.reset()
    load, start, cpu = os.getloadavg()[0], time.perf_counter(), time.process_time()
    summary = run_recording(RecordingSource(**rec), OutputOptions(folder, **output),
                            PoseOptions(detection=variant["detection"]), backend=backend,
                            pipeline=PipelineConfig(**pipe) if pipe else None)
    run_s, done = time.perf_counter() - start, summary["frames_done"]
    pngs = sorted((folder / "overlays").glob("*.png")) or sorted((folder / "overlays").glob("*.jpg"))
    return {"ms_per_frame": 1e3 * run_s / done, "frames_per_second": done / run_s,
            "cpu_ms_per_frame": 1e3 * (time.process_time() - cpu) / done,
            "network_ms_per_frame": 1e3 * clock.seconds / done, "passes_per_frame": clock.runs / done,
            "frames": done, "frames_dropped": summary.get("frames_dropped", 0), "load": [load, os.getloadavg()[0]],
            "png_mb_per_frame": sum(p.stat().st_size for p in pngs) / len(pngs) / 1e6 if pngs else None,
            "speed": summary.get("speed"), "provider": summary["pose_backend"].get("provider", "CPUExecutionProvider")}


def measure(rec: dict, variants: list[dict], work: Path, rounds: int = 1, threads: int = 2,
            side_by_side: tuple[bool, ...] = (True,)) -> dict:
    """``rounds`` times, for each ``side_by_side`` value (``SessionConfig.side_by_side``, one pose
    backend each with ``threads`` intra-op threads, made before any clock starts): the network
    alone, then a run of each of ``variants`` (module doc), one after the other."""
    from pedenv.config import Config
    from pedenv.detection import create_detector

    detection = variants[0]["detection"]
    score = Config().tracking.pose_score_threshold
    backends = {side: create_detector("onnx", detection=detection, score_threshold=score, threads=threads,
                                          **({} if side is None else {"side_by_side": side}))
                for side in side_by_side}
    alone, runs = [], []
    for r in range(rounds):
        for side, backend in backends.items():
            clock = NetworkClock(backend)
            alone.append({**network_alone(rec, backend, clock), "side_by_side": side, "round": r + 1})
            print(f"round {r + 1}{_side(side)}: network alone {alone[-1]['ms_per_frame']:.1f} ms/frame, network "
                  f"{alone[-1]['network_ms_per_frame']:.1f}, CPU {alone[-1]['cpu_ms_per_frame']:.1f} ms/frame",
                  flush=True)
            for variant in variants:
                run = {**run_once(rec, backend, clock, work / "run", variant),
                       "variant": {**variant, "side_by_side": side}, "round": r + 1}
                run["ratio_same_run"] = run["ms_per_frame"] / run["network_ms_per_frame"]
                run["ratio_network_alone"] = run["ms_per_frame"] / alone[-1]["network_ms_per_frame"]
                runs.append(run)
                print(_run_line(run), flush=True)
    return {"alone": alone, "runs": runs}


def _side(side: bool | None) -> str:
    return "" if side is None else f", passes side by side {'on' if side else 'off'}"


def _run_line(run: dict) -> str:
    v = run["variant"]
    name = "mp4" if v["video_out"] else (f"png {v['png_compression']}" if v.get("png_compression") else "jpeg")
    name += f", nice {v['nice']}" if v.get("nice") is not None else ""
    name += _side(v.get("side_by_side"))
    png = f", {run['png_mb_per_frame']:.2f} MB/overlay" if run["png_mb_per_frame"] else ""
    dropped = f", {run['frames_dropped']} dropped" if v.get("realtime") else ""
    return (f"  run ({name}{', realtime' if v.get('realtime') else ''}): {run['ms_per_frame']:.1f} ms/frame "
            f"({run['frames_per_second']:.2f} fps), network {run['network_ms_per_frame']:.1f} in the run, "
            f"{run['passes_per_frame']:.2f} passes/frame, CPU {run['cpu_ms_per_frame']:.1f} ms/frame{png}{dropped}; "
            f"ratio run / network in the run {run['ratio_same_run']:.2f}, run / network alone "
            f"{run['ratio_network_alone']:.2f}; load {run['load'][0]:.1f} -> {run['load'][1]:.1f}")


def _choices(text: str | None) -> list:
    return [None] if text is None else text.split(",")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--video", type=Path, required=True, help="the video (e.g. opencv-doc's vtest.avi)")
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--size", default=None, help="HEIGHTxWIDTH to scale and crop to, e.g. 900x1600")
    parser.add_argument("--detection", default="fast")
    parser.add_argument("--video-out", action="store_true", help="overlay.mp4 instead of a PNG per frame")
    parser.add_argument("--png-compression", default=None, help="fast, none, or both: fast,none (runs each)")
    parser.add_argument("--nice", default=None, help="pipeline.nice of the runs, or several: 0,10 (runs each)")
    parser.add_argument("--rounds", type=int, default=1, help="repeat the network alone and the runs")
    parser.add_argument("--threads", type=int, default=2, help="onnxruntime's intra-op threads (pedenv's default: 2)")
    parser.add_argument("--realtime", action="store_true", help="also a --realtime run: frames done and dropped")
    parser.add_argument("--side-by-side", default=None,
                        help="on, off, or both: on,off (SessionConfig.side_by_side; one backend each, alternated)")
    parser.add_argument("--output-json", type=Path, default=None)
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x")) if args.size else None
    base = {"detection": args.detection, "video_out": args.video_out}
    variants = [{**base, "png_compression": png, "nice": None if nice is None else int(nice)}
                for png in _choices(None if args.video_out else args.png_compression) for nice in _choices(args.nice)]
    if args.realtime:
        variants.append({**variants[0], "realtime": True})
    import pedenv

    print(f"pedenv from {Path(pedenv.__file__).parent}; {args.frames} frames of {args.video.name}"
          f"{' at ' + args.size if args.size else ''}, --detection {args.detection}; load {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        rec = write_recording(args.video, work, args.frames, size)  # type: ignore[arg-type]
        sides = tuple({"on": True, "off": False}[v] for v in args.side_by_side.split(",")) if args.side_by_side \
            else (None,)
        result = measure(rec, variants, work, args.rounds, args.threads, sides)
    result.update(video=args.video.name, size=args.size,
                  detection=args.detection, threads=args.threads)
    for variant in {json.dumps(r["variant"], sort_keys=True): r["variant"] for r in result["runs"]}.values():
        runs = [r for r in result["runs"] if r["variant"] == variant]
        print(f"median over {len(runs)} round(s): {_run_line(_median_run(runs))[2:]}")
    if args.output_json:
        args.output_json.write_text(json.dumps(result, indent=2) + "\n")


def _median_run(runs: list[dict]) -> dict:
    """The run of median ms per frame of ``runs``."""
    return sorted(runs, key=lambda r: r["ms_per_frame"])[len(runs) // 2]


if __name__ == "__main__":
    main()
