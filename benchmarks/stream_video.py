"""``stream`` against ``far`` on a real street video with no ground truth: how many of the people
``far`` reports does ``stream`` also report, frame by frame, and at what cost?

    PYTHONPATH=src python benchmarks/stream_video.py --video vtest.avi
        [--frames 200] [--json out.json] [--keep DIR] [--far-from DIR/far/environment.jsonl]
        [--stream-set FIELD=VALUE ...] [--size 900x1600]

The video (Debian's ``opencv-doc``: ``examples/data/vtest.avi``, 768x576, a pedestrian
street seen from above; ``apt-get install opencv-doc``) is written as a recording of its first
``--frames`` frames at the video's rate (``--size HxW``: each frame scaled to that size, as a
1600x900 camera would see the street), with a GUESSED calibration (focal = image width, 5 m
up, 30 deg down: no usable calibration for the band, so the rows come from the fit) and a
standing ego, and run by :func:`pedenv.apps.run.run_recording` (what ``pedenv run`` calls)
with ``--detection far`` and ``--detection stream`` (default config, the ``fused`` preset).
For every frame, the people far reports (confirmed tracks) are matched to stream's by
IoU >= 0.5: the share found is the figure; stream's units come from its ``run.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

CALIBRATION = """width: {w}
height: {h}
intrinsics: [[{f}, 0, {cx}], [0, {f}, {cy}], [0, 0, 1]]
cam_to_vehicle:
  rotation: [[0, -0.5, 0.8660254037844387], [-1, 0, 0], [0, -0.8660254037844387, -0.5]]
  translation: [0, 0, 5.0]
"""


def write_recording(video: Path, frames: int, out: Path,
                    size: tuple[int, int] | None = None) -> tuple[Path, float]:
    """The first ``frames`` frames of ``video`` as images (and their rate, Hz), a guessed calibration,
    a standing ego; ``size`` (height, width) px: the frames scaled to it."""
    import cv2

    cap = cv2.VideoCapture(str(video))
    rate = cap.get(cv2.CAP_PROP_FPS) or 10.0
    (out / "images").mkdir(parents=True)
    stamps = []
    for i in range(frames):
        ok, bgr = cap.read()
        if not ok:
            break
        if size is not None:
            bgr = cv2.resize(bgr, (size[1], size[0]), interpolation=cv2.INTER_LINEAR)
        cv2.imwrite(str(out / "images" / f"{i:06d}.jpg"), bgr, [cv2.IMWRITE_JPEG_QUALITY, 95])
        stamps.append(i / rate)
    cap.release()
    h, w = bgr.shape[:2]
    (out / "calibration.yaml").write_text(CALIBRATION.format(w=w, h=h, f=float(w), cx=w / 2, cy=h / 2))
    (out / "ego_poses.csv").write_text(f"timestamp,x,y,yaw\n0,0,0,0\n{stamps[-1] + 1.0},0,0,0\n")
    return out, rate


def reported(environment: Path) -> list[np.ndarray]:
    """Per frame the (N, 4) px boxes of the people a run reported."""
    from pedenv.outputs.jsonl import read_environment

    return [np.array([p["box"] for p in line["pedestrians"]], float).reshape(-1, 4)
            for line in read_environment(environment)]


def stream_backend(settings: list[str]):
    """A stream backend with the ``--stream-set`` fields (JSON values), or None: ``run_recording``'s own."""
    if not settings:
        return None
    from dataclasses import replace

    from pedenv.config import Config
    from pedenv.detection import backend_options, create_detector
    from pedenv.detection.config import DetectionConfig
    from pedenv.localization import configure

    fields = {name.strip(): json.loads(value) for name, _, value in (s.partition("=") for s in settings)}
    detection = DetectionConfig.named("stream")
    detection = replace(detection, stream=replace(detection.stream, **fields))
    threshold = configure(Config(), "fused").tracking.pose_score_threshold
    return create_detector("onnx", **backend_options("onnx", None, None, detection, threshold))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--video", type=Path, required=True, help="the video (e.g. opencv-doc's vtest.avi)")
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--keep", type=Path, default=None,
                        help="Write the recording and the runs here (kept) instead of a temporary folder.")
    parser.add_argument("--far-from", type=Path, default=None,
                        help="The environment.jsonl of an earlier far run of the same frames (--keep's far/): "
                             "far is not run again.")
    parser.add_argument("--size", default=None, metavar="HxW", help="Scale the frames to this size, e.g. 900x1600.")
    parser.add_argument("--stream-set", action="append", default=[], metavar="FIELD=VALUE",
                        help="stream: a StreamConfig field (repeatable), e.g. merge_crops=false.")
    args = parser.parse_args(argv)

    from pedenv.apps.options import PoseOptions, RecordingSource
    from pedenv.apps.run import run_recording
    from pedenv.boxes import iou_matrix

    results: dict = {"video": args.video.name, "size": args.size, "load_at_start": os.getloadavg()[0]}
    with tempfile.TemporaryDirectory() as scratch:
        tmp = args.keep or Path(scratch)
        size = tuple(int(v) for v in args.size.lower().split("x")) if args.size else None
        rec, rate = write_recording(args.video, args.frames, Path(tmp) / "recording", size)
        boxes = {}
        if args.far_from:
            boxes["far"] = reported(args.far_from)[:args.frames]
        for mode in ("stream",) if args.far_from else ("far", "stream"):
            t0 = time.perf_counter()
            source = RecordingSource(calibration=rec / "calibration.yaml", ego_poses=rec / "ego_poses.csv",
                                     images=rec / "images", fps=rate)
            summary = run_recording(source, Path(tmp) / mode, PoseOptions(detection=mode),
                                    backend=stream_backend(args.stream_set) if mode == "stream" else None)
            results[mode] = {"seconds_per_frame": (time.perf_counter() - t0) / max(summary["frames_done"], 1),
                             "stream": summary["pose_backend"].get("stream")}
            boxes[mode] = reported(Path(tmp) / mode / "environment.jsonl")
    far_n = found = 0
    for a, b in zip(boxes["far"], boxes["stream"]):
        far_n += len(a)
        if len(a) and len(b):
            found += int((iou_matrix(a, b).max(axis=1) >= 0.5).sum())
    results.update(frames=len(boxes["far"]), far_reported=far_n, stream_reported=sum(len(b) for b in boxes["stream"]),
                   far_also_in_stream=found / max(far_n, 1), load_at_end=os.getloadavg()[0])
    print(json.dumps(results, indent=2))
    if args.json:
        args.json.write_text(json.dumps(results, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
