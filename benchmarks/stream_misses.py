"""Which of ``far``'s people ``stream`` does not report on a real video, frame by frame, and why.

    PYTHONPATH=src python benchmarks/stream_misses.py --recording DIR/recording --far-from DIR/far/environment.jsonl
        [--frames 795] [--json out.json] [--out DIR/stream_traced] [--stream-set FIELD=VALUE ...]

``DIR`` is ``benchmarks/stream_video.py --keep DIR``'s folder (the recording and far's run). The
script runs ``stream`` over the recording as ``pedenv run`` does (:func:`pedenv.apps.run.run_recording`,
the fused preset) with its :class:`~pedenv.detection.stream.StreamState` traced: per frame the tracks it
was given, the whole-frame pass's persons, the band tiles it ran, the tracks it searched in packed
crops and whether their crop got into an input, and the persons it returned. Every person far
reported (a track's detection, IoU >= 0.5 with none of stream's reports in that frame) is then put
in the first class that holds it (``CLASSES``). Far's side is described too: the age (detections
so far) of far's track at that frame and how many frames far reports that track in all.
"""

from __future__ import annotations

import argparse
import json
import os
from collections import Counter
from pathlib import Path

import numpy as np

from pedenv.boxes import iou_matrix

#: The classes of a far person stream does not report, in the order they are tested.
CLASSES = (
    "cold start frame",
    "stream detected it, its tracker did not report it",
    "stream reported it, box IoU 0.3-0.5 (same person, other box)",
    "a stream track was there, searched in a crop, not found",
    "a stream track was there, its crop got no input (budget)",
    "a stream track was there, not searched (whole-frame box over it)",
    "no stream track, in a band tile run this frame, not found",
    "no stream track, no band tile over it this frame",
)
#: The second view (:func:`settled`): far's tracks reported in at least this many frames, from this age on.
SETTLED_FRAMES = 10
SETTLED_AGE = 3
#: Overlap of a far box with a stream track's box (predicted or searched) for the track to be "there".
NEAR_IOU = 0.3


class Trace:
    """Per frame what :class:`~pedenv.detection.stream.StreamState` saw and did (lists of dicts, frame order)."""

    def __init__(self) -> None:
        self.frames: list[dict] = []

    def install(self) -> None:
        """Wrap ``StreamState.detect_frame``, ``StreamState._packed`` and the module's ``run_level``."""
        import pedenv.detection.stream as stream
        from pedenv.detection.packing import pack_tallest_first

        trace, run_level, detect_frame, packed = self, stream.run_level, stream.StreamState.detect_frame, \
            stream.StreamState._packed
        run_packed = stream.run_packed

        def traced_run_mosaics(*args, **kwargs):
            results, passes = run_packed(*args, **kwargs)
            trace.frames[-1]["crop_found"] = [(d.boxes.copy(), d.scores.copy(), cut.copy()) for d, cut in results]
            return results, passes

        def traced_run_level(*args, **kwargs):
            parts = run_level(*args, **kwargs)
            passes = args[2]
            trace.frames[-1]["passes"].append(([p.region for p in passes], [p.kind for p in passes],
                                               [d.boxes.copy() for d, _ in parts]))
            return parts

        def traced_detect_frame(self, image, geometry, timestamp, tracks=None):
            ids, boxes, hits = (tracks.ids, tracks.boxes, tracks.hits) if tracks is not None else (
                np.zeros(0), np.zeros((0, 4)), np.zeros(0))
            trace.frames.append({"t": float(timestamp), "ids": np.asarray(ids).copy(),
                                 "predicted": np.asarray(boxes, float).reshape(-1, 4).copy(),
                                 "hits": np.asarray(hits).copy(), "passes": [], "searched": np.zeros((0, 4)),
                                 "placed": np.zeros((0, 4)), "unplaced": np.zeros((0, 4)), "crop_found": []})
            dets = detect_frame(self, image, geometry, timestamp, tracks)
            frame = trace.frames[-1]
            frame.update(dets=dets.boxes.copy(), scores=dets.scores.copy(),
                         cold=self.accounts.cold_starts > trace.cold_seen)
            trace.cold_seen = self.accounts.cold_starts
            return dets

        def traced_packed(self, image, dets, low, boxes, rows, track_crops, limit, settings):
            size = self.config.stream.packed_size
            placed = {p.item for p in pack_tallest_first(track_crops[0], size, max_inputs=limit)}
            searched = boxes[0]
            rows_in = [r for i, group in enumerate(rows) if i in placed for r in group]
            rows_out = [r for i, group in enumerate(rows) if i not in placed for r in group]
            trace.frames[-1].update(searched=searched.copy(), placed=searched[rows_in].reshape(-1, 4).copy(),
                                    unplaced=searched[rows_out].reshape(-1, 4).copy())
            return packed(self, image, dets, low, boxes, rows, track_crops, limit, settings)

        self.cold_seen = 0
        stream.run_level = traced_run_level
        stream.run_packed = traced_run_mosaics
        stream.StreamState.detect_frame = traced_detect_frame
        stream.StreamState._packed = traced_packed


def _hit(box: np.ndarray, boxes: np.ndarray, iou: float) -> bool:
    return bool(len(boxes)) and float(iou_matrix(box[None], np.asarray(boxes, float).reshape(-1, 4)).max()) >= iou


def _in_tile(box: np.ndarray, frame: dict) -> bool:
    """The box lies inside a band tile this frame ran (not the whole-frame pass)."""
    for regions, kinds, _ in frame["passes"][1:2]:
        for (x0, y0, x1, y1), kind in zip(regions, kinds):
            if kind != "full" and x0 <= box[0] and box[2] <= x1 and y0 <= box[1] and box[3] <= y1:
                return True
    return False


def classify(box: np.ndarray, frame: dict, stream_reported: np.ndarray) -> str:
    """The class (``CLASSES``) of a far person ``box`` (4,) px stream did not report in ``frame``."""
    if frame["cold"]:
        return CLASSES[0]
    if _hit(box, frame["dets"], 0.5):
        return CLASSES[1]
    if _hit(box, stream_reported, 0.3):
        return CLASSES[2]
    near = np.concatenate([frame["predicted"], frame["searched"]])
    if _hit(box, near, NEAR_IOU):
        if _hit(box, frame["placed"], NEAR_IOU):
            return CLASSES[3]
        if _hit(box, frame["unplaced"], NEAR_IOU):
            return CLASSES[4]
        return CLASSES[5]
    return CLASSES[6] if _in_tile(box, frame) else CLASSES[7]


def detail(box: np.ndarray, frame: dict) -> str:
    """What stream's passes saw of a missed far person ``box`` (4,) px: its best-overlapping
    person in the packed crops (score, cut) or in the frame's returned persons (score)."""
    best = (0.0, "")
    for boxes, scores, cut in frame["crop_found"]:
        if len(boxes):
            overlap = iou_matrix(box[None], boxes)[0]
            i = int(np.argmax(overlap))
            if overlap[i] > best[0]:
                cut_note = " cut" if cut[i] else ""
                best = (float(overlap[i]), f"crop: IoU {overlap[i]:.2f} score {scores[i]:.2f}{cut_note}")
    if len(frame["dets"]):
        overlap = iou_matrix(box[None], frame["dets"])[0]
        i = int(np.argmax(overlap))
        if overlap[i] >= 0.3:
            return f"{best[1]}; returned: IoU {overlap[i]:.2f} score {frame['scores'][i]:.2f}".lstrip("; ")
    return best[1] or "nothing near"


def far_people(environment: Path, frames: int) -> list[list[dict]]:
    """Per frame far's reported people: ``box`` (4,) px, ``track_id``, ``age`` (detections so far)."""
    from pedenv.outputs.jsonl import read_environment

    return [[{"box": np.asarray(p["box"], float), "track_id": p["track_id"], "age": p["age"]}
             for p in line["pedestrians"]] for line in list(read_environment(environment))[:frames]]


def account(far: list[list[dict]], stream: list[np.ndarray], trace: Trace) -> dict:
    """Far's people, those stream reports, and the misses by class, far track age and height."""
    lifetime = Counter(p["track_id"] for people in far for p in people)
    total = found = 0
    misses: Counter = Counter()
    rows = []
    for f, (people, reported, frame) in enumerate(zip(far, stream, trace.frames)):
        for p in people:
            total += 1
            if _hit(p["box"], reported, 0.5):
                found += 1
                continue
            cls = classify(p["box"], frame, reported)
            misses[cls] += 1
            rows.append({"frame": f, "class": CLASSES.index(cls), "far_id": p["track_id"], "far_age": p["age"],
                         "far_frames": lifetime[p["track_id"]], "height_px": float(p["box"][3] - p["box"][1]),
                         "box": [round(float(v), 1) for v in p["box"]], "detail": detail(p["box"], frame)})
    return {"far_people": total, "stream_also": found, "share": found / max(total, 1),
            "misses_by_class": {c: misses[c] for c in CLASSES}, "settled_view": settled(far, stream),
            "misses": rows}


def settled(far: list[list[dict]], stream: list[np.ndarray]) -> dict:
    """A second view, apart from the figure above: only far's people of tracks far reports in at
    least :data:`SETTLED_FRAMES` frames, from their :data:`SETTLED_AGE`-th detection on (far's
    one-frame tracks, id switches and first sightings left out)."""
    lifetime = Counter(p["track_id"] for people in far for p in people)
    total = found = 0
    for people, reported in zip(far, stream):
        for p in people:
            if lifetime[p["track_id"]] >= SETTLED_FRAMES and p["age"] >= SETTLED_AGE:
                total += 1
                found += int(_hit(p["box"], reported, 0.5))
    return {"far_track_frames_at_least": SETTLED_FRAMES, "far_track_age_at_least": SETTLED_AGE,
            "far_people": total, "stream_also": found, "share": found / max(total, 1)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--recording", type=Path, required=True, help="stream_video.py --keep DIR's recording/.")
    parser.add_argument("--far-from", type=Path, required=True, help="far's environment.jsonl of the same frames.")
    parser.add_argument("--frames", type=int, default=100000)
    parser.add_argument("--fps", type=float, default=10.0, help="The recording's rate (vtest.avi: 10 Hz).")
    parser.add_argument("--out", type=Path, default=None, help="stream's run folder (default: next to --recording).")
    parser.add_argument("--json", type=Path, default=None)
    parser.add_argument("--stream-set", action="append", default=[], metavar="FIELD=VALUE")
    args = parser.parse_args(argv)

    import shutil

    from stream_video import reported, stream_backend

    from pedenv.apps.options import PoseOptions, RecordingSource
    from pedenv.apps.run import run_recording

    far = far_people(args.far_from, args.frames)
    rec = args.recording
    images = sorted((rec / "images").iterdir())[:len(far)]
    cut = rec.parent / f"recording_{len(far)}"
    if len(images) < len(list((rec / "images").iterdir())) and not cut.exists():
        (cut / "images").mkdir(parents=True)
        for image in images:
            os.link(image, cut / "images" / image.name)
        for name in ("calibration.yaml", "ego_poses.csv"):
            shutil.copy(rec / name, cut / name)
        rec = cut
    elif cut.exists():
        rec = cut
    trace = Trace()
    trace.install()
    out = args.out or rec.parent / "stream_traced"
    if (out / ".pedenv-output").exists():
        shutil.rmtree(out)
    source = RecordingSource(calibration=rec / "calibration.yaml", ego_poses=rec / "ego_poses.csv",
                             images=rec / "images", fps=args.fps)
    summary = run_recording(source, out, PoseOptions(detection="stream"), backend=stream_backend(args.stream_set))
    result = account(far, reported(out / "environment.jsonl"), trace)
    result.update(stream=summary["pose_backend"].get("stream"), load=os.getloadavg()[0])
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "misses"}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
