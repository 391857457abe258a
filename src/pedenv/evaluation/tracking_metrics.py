"""Tracking quality against ground-truth ids with ``motmetrics`` (MOTA, IDF1, ID switches).

Hypotheses and ground truth are matched in the image by box IoU (distance 1 - IoU,
pairs below ``min_iou`` cannot match), so the tracker is judged on its own ground,
independently of the position error.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pedenv.boxes import iou_matrix


class TrackingAccumulator:
    """One ``motmetrics.MOTAccumulator`` per scene; frames without ids are skipped."""

    def __init__(self, min_iou: float = 0.5) -> None:
        import motmetrics  # imported here: only evaluation needs it

        self._mm = motmetrics
        self.min_iou = min_iou
        self.scenes: dict[str, Any] = {}  # motmetrics.MOTAccumulator per scene (motmetrics has no types)

    def add(self, scene: str, gt_ids: np.ndarray, gt_boxes: np.ndarray, track_ids: np.ndarray,
            boxes: np.ndarray) -> None:
        """One labelled frame: gt_ids (M,), gt_boxes (M, 4), track_ids (N,), boxes (N, 4) pixels."""
        if len(gt_ids) and np.any(gt_ids < 0):
            return
        acc = self.scenes.get(scene)
        if acc is None:
            acc = self.scenes[scene] = self._mm.MOTAccumulator(auto_id=True)
        dist = 1.0 - iou_matrix(gt_boxes, boxes)
        dist[dist > 1.0 - self.min_iou] = np.nan
        acc.update(gt_ids.tolist(), track_ids.tolist(), dist)

    def summary(self) -> dict | None:
        """``{"mota", "idf1", "id_switches", "motp_iou", "false_positives", "misses", "objects"}`` over all
        scenes (``objects``: labelled boxes; MOTA = 1 - (misses + false_positives + id_switches) / objects),
        None without ids."""
        if not self.scenes:
            return None
        mh = self._mm.metrics.create()
        df = mh.compute_many(list(self.scenes.values()), names=list(self.scenes),
                             metrics=["mota", "idf1", "num_switches", "motp", "num_false_positives",
                                      "num_misses", "num_objects"], generate_overall=True)
        row = df.loc["OVERALL"]
        return {"mota": float(row["mota"]), "idf1": float(row["idf1"]), "id_switches": int(row["num_switches"]),
                "motp_iou": float(1.0 - row["motp"]) if np.isfinite(row["motp"]) else None,
                "false_positives": int(row["num_false_positives"]), "misses": int(row["num_misses"]),
                "objects": int(row["num_objects"])}
