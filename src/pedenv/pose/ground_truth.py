"""The ``ground-truth`` backend: the exact 2D skeletons that come with the data.

The paper evaluated its CARLA recordings this way (score 1 for every keypoint).
"""

from __future__ import annotations

import numpy as np

from pedenv.errors import InputError
from pedenv.records import Detections, Frame, PredictedTracks


class GroundTruthPose:
    """Detections from ``frame.ground_truth.keypoints``; unseen keypoints get confidence 0.

    Frames without labelled skeletons (e.g. nuScenes sweeps) must carry detections
    already; a frame with neither is an error naming the frame.
    """

    name = "ground-truth"

    def __call__(self, frame: Frame, tracks: PredictedTracks | None = None) -> Detections:  # noqa: ARG002 - sees no tracks
        gt = frame.ground_truth
        if gt is None or gt.keypoints is None:
            if frame.detections is not None:
                return frame.detections
            raise InputError(
                f"frame {frame.index} of {frame.scene or 'the sequence'}: "
                "no ground-truth skeletons for the 'ground-truth' pose backend"
            )
        assert gt.visible is not None  # GroundTruth sets visible whenever it has keypoints
        conf = gt.visible.astype(np.float64)
        keep = gt.visible.any(axis=1)
        return Detections(gt.keypoints[keep], conf[keep])
