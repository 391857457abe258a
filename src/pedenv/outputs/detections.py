"""``detections.json`` of ``pedenv detect``: the 2D skeletons found in each image.

::

    {"images": [{"file": ..., "width": ..., "height": ..., "backend": ..., "drawn": ...,
                 "persons": [{"box": [u_min, v_min, u_max, v_max], "score": ...,
                              "keypoints": [{"name": "nose", "u": ..., "v": ..., "confidence": ...}, ...]}]}],
     "failed": [{"file": ..., "error": ...}]}

Pixels (u right, v down) of the original image; strict JSON (no NaN).
"""

from __future__ import annotations

import json
from pathlib import Path

from pedenv.errors import InputError
from pedenv.paths import writable_file
from pedenv.records import Detections
from pedenv.skeleton import KEYPOINT_NAMES


def detections_to_dict(detections: Detections, decimals: int = 2) -> list[dict]:
    """JSON-ready persons: box, score and the 17 named keypoints (u, v pixels, confidence)."""
    persons = []
    for kp, conf, box, score in zip(detections.keypoints, detections.confidences, detections.boxes, detections.scores):
        persons.append({
            "box": [round(float(x), decimals) for x in box],
            "score": round(float(score), 4),
            "keypoints": [{"name": n, "u": round(float(p[0]), decimals), "v": round(float(p[1]), decimals),
                           "confidence": round(float(c), 4)} for n, p, c in zip(KEYPOINT_NAMES, kp, conf)],
        })
    return persons


def write_detections(path: str | Path, images: list[dict], failed: list[dict] | None = None) -> Path:
    """Write ``{"images": images, "failed": failed}`` to ``path`` as strict JSON; returns the path."""
    path = writable_file(path, "detections file")
    try:
        path.write_text(json.dumps({"images": images, "failed": failed or []}, indent=1, allow_nan=False) + "\n")
    except OSError as exc:
        raise InputError(f"detections file {path} cannot be written: {exc.strerror or exc}") from None
    return path


def unique_names(paths: list[Path], suffix: str) -> list[str]:
    """A distinct file name ``<stem><suffix>`` per input path: a stem met again gets ``-2``,
    ``-3``, ... (``a/img.png`` and ``b/img.png`` -> ``img_pose.png``, ``img-2_pose.png``)."""
    taken: set[str] = set()
    names = []
    for p in paths:
        stem, k = p.stem, 1
        name = f"{stem}{suffix}"
        while name in taken:
            k += 1
            name = f"{stem}-{k}{suffix}"
        taken.add(name)
        names.append(name)
    return names
