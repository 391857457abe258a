"""pedenv's skeleton side file next to a nuScenes-format dataset (nuScenes has no skeletons).

``<dataroot>/pedenv_skeletons.json``::

    {"format": "pedenv-skeletons", "version": 1, "layout": "coco-17",
     "sample_data": {"<CAM_FRONT sample_data token>": [
         {"instance_token": "<instance token>",      # the person's nuScenes instance
          "keypoints": [[u, v], ... 17],              # pixels, COCO-17 order
          "visible": [true, ... 17],                  # which keypoints are seen
          "box": [u_min, v_min, u_max, v_max]},       # optional: the person's exact 2D box, pixels
         ...]}}

Written by :func:`pedenv.datasets.nuscenes_export.write_nuscenes` for every exported frame,
keyframes and sweeps alike; read by :class:`pedenv.datasets.nuscenes.NuScenesDataset`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pedenv.errors import InputError, check_array
from pedenv.skeleton import NUM_KEYPOINTS
from pedenv.structured_text import load_json

SIDE_FILE_NAME = "pedenv_skeletons.json"
FORMAT = "pedenv-skeletons"


@dataclass(frozen=True)
class Skeleton:
    """One person's exact 2D skeleton in one image.

    keypoints: (17, 2) pixels; visible: (17,) bool; box: optional (4,) pixels.
    """

    instance_token: str
    keypoints: np.ndarray
    visible: np.ndarray
    box: np.ndarray | None = None


def skeleton_entry(instance_token: str, keypoints: np.ndarray, visible: np.ndarray, box: np.ndarray | None) -> dict:
    """The JSON entry of one skeleton (see the module docstring)."""
    entry = {"instance_token": instance_token, "keypoints": np.asarray(keypoints, float).tolist(),
             "visible": np.asarray(visible, bool).tolist()}
    if box is not None:
        entry["box"] = np.asarray(box, float).tolist()
    return entry


def write_side_file(path: Path, entries: dict[str, list[dict]]) -> None:
    """Write ``{sample_data token: [entry, ...]}`` as a side file at ``path``."""
    path.write_text(
        json.dumps({"format": FORMAT, "version": 1, "layout": "coco-17", "sample_data": entries}, allow_nan=False)
    )


def read_side_file(path: Path) -> dict[str, list[Skeleton]]:
    """``{sample_data token: [Skeleton, ...]}`` from a side file; bad content names the file and field."""
    data = load_json(path, "the skeleton side file")
    if not isinstance(data, dict) or data.get("format") != FORMAT or not isinstance(data.get("sample_data"), dict):
        raise InputError(
            f"{path}: not a pedenv skeleton side file (needs format={FORMAT!r} and a 'sample_data' object)"
        )
    out: dict[str, list[Skeleton]] = {}
    for token, entries in data["sample_data"].items():
        skeletons = []
        for i, e in enumerate(entries):
            where = f"{path}: sample_data {token} entry {i}"
            if not isinstance(e, dict) or not {"instance_token", "keypoints", "visible"} <= e.keys():
                raise InputError(f"{where}: needs instance_token, keypoints, visible")
            box = None if e.get("box") is None else check_array(f"{where} box", e["box"], (4,))
            skeletons.append(Skeleton(str(e["instance_token"]),
                                      check_array(f"{where} keypoints", e["keypoints"], (NUM_KEYPOINTS, 2)),
                                      check_array(f"{where} visible", e["visible"], (NUM_KEYPOINTS,), dtype=bool), box))
        out[token] = skeletons
    return out
