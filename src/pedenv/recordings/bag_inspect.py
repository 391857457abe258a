"""``pedenv inspect-bag``: what a bag holds (topics, types, counts, rates, the tf tree) and what ``run`` would use."""

from __future__ import annotations

import struct
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.errors import InputError
from pedenv.recordings.bag import load_bag_recording
from pedenv.recordings.bag_source import BagSource
from pedenv.recordings.bag_tf import TransformTree
from pedenv.recordings.bag_topics import TF_TYPE, BagOptions


def inspect_bag(path: str | Path, options: BagOptions | None = None) -> dict:
    """A JSON-ready summary: ``topics`` (name, type, count, rate_hz), ``tf`` (parent -> child
    links, static or not), ``run`` (the topics and frames ``pedenv run --bag`` would use) or
    ``run_error`` (the one line it would fail with)."""
    opts = options or BagOptions()
    with BagSource(path, max_message_bytes=opts.max_message_bytes) as bag:
        spans = index_spans(bag.reader)
        topics = bag.log_spans() if spans is None else {
            name: replace(t, first_ns=spans.get(name, (0, 0))[0], last_ns=spans.get(name, (0, 0))[1])
            for name, t in bag.topics.items()}
        tree = TransformTree(str(path))
        for m in bag.messages(bag.topics_of(TF_TYPE), to_the_cut=True):
            tree.add(m.msg, static=m.topic.endswith("tf_static"), topic=m.topic, index=m.index)
        kind = bag.kind
    summary: dict = {
        "bag": str(path), "kind": kind,
        "topics": [{"name": t.name, "type": t.msgtype.replace("/msg/", "/"), "count": t.count,
                    "rate_hz": None if t.rate_hz is None else round(t.rate_hz, 3)} for t in topics.values()],
        "tf": [{"parent": p, "child": c, "static": True} for c, (p, _) in sorted(tree.static.items())]
        + [{"parent": s.parent, "child": c, "static": False, "samples": len(s.stamps)}
           for c, s in sorted(tree.dynamic.items())],
    }
    try:
        rec = load_bag_recording(path, opts)
    except InputError as exc:
        summary["run_error"] = str(exc)
        return summary
    c = rec.choice
    summary["run"] = {"images": c.image_topic, "camera_info": c.camera_info_topic,
                      "ego": c.odometry_topic or f"/tf {c.world_frame} -> {c.vehicle_frame}",
                      "camera_frame": c.camera_frame, "vehicle_frame": c.vehicle_frame, "world_frame": c.world_frame,
                      "frames": len(rec), "image_size": [rec.camera.width, rec.camera.height],
                      "distortion": rec.camera_model.model if rec.camera_model.distorted else "none"}
    return summary


def index_spans(reader: Any) -> dict[str, tuple[int, int]] | None:
    """Each topic's first and last receive time (ns) from the bag's indexes, nothing decompressed:
    MCAP message indexes, ROS 1 index records, a sqlite3 query; None for a bag without them
    (an MCAP file without a summary: its messages are read)."""
    from rosbags.rosbag1 import Reader as Reader1
    from rosbags.rosbag2.storage_mcap import McapReader
    from rosbags.rosbag2.storage_sqlite3 import Sqlite3Reader

    inner = getattr(reader, "storage", reader)
    parts = [*getattr(inner, "storages", []), *([inner] if not hasattr(inner, "storages") else [])]
    spans: dict[str, tuple[int, int]] = {}
    for part in parts:
        if isinstance(part, Reader1):
            found = {c.topic: (ix[0].time, ix[-1].time) for c in part.connections if (ix := part.indexes.get(c.id))}
        elif isinstance(part, McapReader) and part.chunks:
            found = _mcap_spans(part)
        elif isinstance(part, Sqlite3Reader) and part.dbconn is not None:
            topics = {c.id: c.topic for c in part.connections}
            rows = part.dbconn.cursor().execute("SELECT topic_id, MIN(timestamp), MAX(timestamp) FROM messages "
                                                "GROUP BY topic_id")
            found = {topics[t]: (int(lo), int(hi)) for t, lo, hi in rows if t in topics}
        else:
            return None
        for topic, (lo, hi) in found.items():
            old = spans.get(topic, (lo, hi))
            spans[topic] = (min(old[0], lo), max(old[1], hi))
    return spans


def _mcap_spans(reader: Any) -> dict[str, tuple[int, int]]:
    """First and last log time per topic from the message index records after each MCAP chunk."""
    topics = {c.id: c.topic for c in reader.connections}
    spans: dict[str, tuple[int, int]] = {}
    bio = reader.bio
    for chunk in reader.chunks:
        for channel, offset in chunk.message_index_offsets.items():
            bio.seek(offset)
            op, _, _, size = struct.unpack("<BQHI", bio.read(15))
            if op != 0x07 or channel not in topics or size < 16 or size % 16:
                continue
            stamps = np.frombuffer(bio.read(size), "<u8")[::2]  # (log time, offset) pairs, in any order
            times = (int(stamps.min()), int(stamps.max()))
            old = spans.get(topics[channel], times)
            spans[topics[channel]] = (min(old[0], times[0]), max(old[1], times[1]))
    return spans


def format_inspection(summary: dict) -> str:
    """The summary of :func:`inspect_bag` as text lines."""
    lines = [f"{summary['bag']} ({summary['kind']})", "topics:"]
    width = max((len(t["name"]) for t in summary["topics"]), default=0)
    for t in summary["topics"]:
        rate = "" if t["rate_hz"] is None else f"  {t['rate_hz']:.2f} Hz"
        lines.append(f"  {t['name']:<{width}}  {t['type']}  {t['count']} msgs{rate}")
    lines.append("tf frames:" if summary["tf"] else "tf frames: none")
    for link in summary["tf"]:
        what = "static" if link["static"] else f"{link['samples']} samples"
        lines.append(f"  {link['parent']} -> {link['child']} ({what})")
    if "run" in summary:
        lines.append("pedenv run --bag would use:")
        lines += [f"  {k}: {v}" for k, v in summary["run"].items()]
    else:
        lines.append(f"pedenv run --bag would stop: {summary['run_error']}")
    return "\n".join(lines)
