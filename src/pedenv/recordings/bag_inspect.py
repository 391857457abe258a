"""``pedenv inspect-bag``: what a bag holds (topics, types, counts, rates, the tf tree) and what ``run`` would use."""

from __future__ import annotations

from pathlib import Path

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
        topics = bag.log_spans()
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
