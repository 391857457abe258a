"""``pedenv run`` end to end against the network's own time, on a real video.

    PYTHONPATH=src python benchmarks/run_pipeline.py [--video vtest.avi] [--frames 100] [--size 1600x900]
        [--detection fast] [--video-out] [--realtime] [--output-json FILE]

The video (default: ``vtest.avi``, the 768x576 street video of Debian's ``opencv-doc``,
``/usr/share/doc/opencv-doc/examples/data/vtest.avi``) is cut to its first ``--frames`` frames,
optionally scaled and centre-cropped to ``--size`` (e.g. 1600x900, nuScenes' camera), and
written as a recording (MJPG video, a GUESSED static camera 5 m up looking 30 deg down, a
standing ego) into a temporary folder. Then, with one pose backend (``--detection``, made
before the clock starts):

1. ``network alone``: every frame read, detected and given to the model (the default, fused
   preset, whose re-detection crops run the network too), nothing written;
2. ``run``: :func:`pedenv.apps.run.run_recording` (what ``pedenv run`` calls, overlays on: a
   PNG per frame, or ``--video-out``), wall time from the call to its return;
3. with ``--realtime``: the run once more at the recording's own rate: frames done and dropped.

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

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")


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
    """Wraps a backend's ``infer`` (its session runs) to add up their seconds and count them."""

    def __init__(self, backend) -> None:
        self.seconds, self.runs = 0.0, 0
        backend = backend if hasattr(backend, "infer") else backend.backend  # stream: its OnnxPose
        infer = backend.infer

        def timed(tensor):
            start = time.perf_counter()
            try:
                return infer(tensor)
            finally:
                self.seconds += time.perf_counter() - start
                self.runs += 1

        backend.infer = timed

    def reset(self) -> None:
        self.seconds, self.runs = 0.0, 0


def measure(rec: dict, detection: str, video_out: bool, work: Path, realtime: bool = False) -> dict:
    """The network alone and the run on the recording ``rec`` (module doc); with ``realtime``
    also a ``--realtime`` run (this checkout's pedenv only)."""
    from dataclasses import replace

    from pedenv.apps.options import OutputOptions, PoseOptions, RecordingSource
    from pedenv.apps.run import run_recording
    from pedenv.config import Config
    from pedenv.model import PedestrianEnvironmentModel
    from pedenv.pose.base import create_pose_backend
    from pedenv.pose.redetect import with_redetection
    from pedenv.recordings.footage import load_recording

    cfg = Config()
    backend = create_pose_backend("onnx", detection=detection, score_threshold=cfg.tracking.pose_score_threshold)
    clock = NetworkClock(backend)
    load = [os.getloadavg()[0]]
    frames = 0
    model = PedestrianEnvironmentModel(cfg)
    middle = with_redetection(backend, model, cfg.redetect)  # as run_recording wraps it
    start, cpu = time.perf_counter(), time.process_time()
    for frame in load_recording(**rec).frames():
        model.update(replace(frame, detections=middle(frame)))
        frames += 1
    alone_s = time.perf_counter() - start
    alone = {"ms_per_frame": 1e3 * alone_s / frames, "network_ms_per_frame": 1e3 * clock.seconds / frames,
             "cpu_ms_per_frame": 1e3 * (time.process_time() - cpu) / frames}
    clock.reset()
    start, cpu = time.perf_counter(), time.process_time()
    summary = run_recording(RecordingSource(**rec), OutputOptions(work / "run", video_out=video_out),
                            PoseOptions(detection=detection), backend=backend)
    run_s = time.perf_counter() - start
    load.append(os.getloadavg()[0])
    done = summary["frames_done"]
    run = {"ms_per_frame": 1e3 * run_s / done, "frames_per_second": done / run_s,
           "cpu_ms_per_frame": 1e3 * (time.process_time() - cpu) / done,
           "network_ms_per_frame": 1e3 * clock.seconds / done, "passes_per_frame": clock.runs / done,
           "frames": done, "speed": summary.get("speed")}
    if realtime:  # the same recording once more, taken at its own rate (10 Hz for vtest.avi)
        from pedenv.apps.pipeline import PipelineConfig

        live = run_recording(RecordingSource(**rec), OutputOptions(work / "live", video_out=video_out),
                             PoseOptions(detection=detection), backend=backend, pipeline=PipelineConfig(realtime=True))
        run["realtime"] = {"frames_done": live["frames_done"], "frames_dropped": live["frames_dropped"],
                           "latency_ms": live["speed"]["latency_ms"]}
    return {"frames": frames, "load": load, "alone": alone, "run": run,
            "ratio_same_run": run["ms_per_frame"] / run["network_ms_per_frame"],
            "ratio_network_alone": run["ms_per_frame"] / alone["network_ms_per_frame"],
            "provider": summary["pose_backend"].get("provider", "CPUExecutionProvider (main: CPU only)")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--video", type=Path, default=VTEST)
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--size", default=None, help="HEIGHTxWIDTH to scale and crop to, e.g. 900x1600")
    parser.add_argument("--detection", default="fast")
    parser.add_argument("--video-out", action="store_true", help="overlay.mp4 instead of a PNG per frame")
    parser.add_argument("--realtime", action="store_true", help="also a --realtime run: frames done and dropped")
    parser.add_argument("--output-json", type=Path, default=None)
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x")) if args.size else None
    import pedenv

    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        rec = write_recording(args.video, work, args.frames, size)  # type: ignore[arg-type]
        result = measure(rec, args.detection, args.video_out, work, args.realtime)
    result.update(pedenv=str(Path(pedenv.__file__).parent), video=str(args.video), size=args.size,
                  detection=args.detection, overlays="mp4" if args.video_out else "png")
    r, a = result["run"], result["alone"]
    print(f"pedenv from {result['pedenv']}; {result['frames']} frames of {args.video.name}"
          f"{' at ' + args.size if args.size else ''}, --detection {args.detection}, overlays {result['overlays']}, "
          f"{result['provider']}; load {result['load'][0]:.1f} -> {result['load'][1]:.1f}")
    print(f"network alone: {a['ms_per_frame']:.1f} ms/frame read + detect + model, network "
          f"{a['network_ms_per_frame']:.1f}, "
          f"CPU {a['cpu_ms_per_frame']:.1f} ms/frame (all threads)")
    print(f"pedenv run:    {r['ms_per_frame']:.1f} ms/frame ({r['frames_per_second']:.2f} fps), network "
          f"{r['network_ms_per_frame']:.1f} ms/frame in the run, {r['passes_per_frame']:.2f} passes/frame, "
          f"CPU {r['cpu_ms_per_frame']:.1f} ms/frame")
    print(f"ratio run / network in the same run: {result['ratio_same_run']:.2f}; "
          f"run / network alone: {result['ratio_network_alone']:.2f}")
    if r["speed"]:
        lat = r["speed"]["latency_ms"]
        print(f"run.json: {r['speed']['frames_per_second']:.2f} fps, latency median {lat['median']:.0f} ms, "
              f"p95 {lat['p95']:.0f} ms")
    if "realtime" in r:
        live = r["realtime"]
        print(f"--realtime: {live['frames_done']} frames done, {live['frames_dropped']} dropped (the model was busy), "
              f"latency median {live['latency_ms']['median']:.0f} ms")
    if args.output_json:
        args.output_json.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
