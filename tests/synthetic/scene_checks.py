"""Helper comparing scenes field by field (imported by the synthetic tests)."""

from __future__ import annotations

import numpy as np

from pedenv.records import Scene


def _same(a, b) -> bool:
    if a is None or b is None:
        return a is None and b is None
    return np.array_equal(a, b)


def assert_scenes_equal(a: Scene, b: Scene) -> None:
    """Every field of every frame is identical (arrays compared exactly)."""
    assert (a.name, a.description, len(a.frames)) == (b.name, b.description, len(b.frames))
    for fa, fb in zip(a.frames, b.frames):
        assert (fa.index, fa.timestamp, fa.scene, fa.image_path) == (fb.index, fb.timestamp, fb.scene, fb.image_path)
        assert (fa.camera.width, fa.camera.height) == (fb.camera.width, fb.camera.height)
        for x, y in ((fa.camera.intrinsics, fb.camera.intrinsics), (fa.camera.cam_to_vehicle, fb.camera.cam_to_vehicle),
                     (fa.ego.translation, fb.ego.translation), (fa.ego.rotation, fb.ego.rotation)):
            assert np.array_equal(x, y)
        for ga, gb, fields in ((fa.ground_truth, fb.ground_truth,
                                ("ids", "positions", "boxes", "keypoints", "visible", "heights", "keypoints_3d")),
                               (fa.detections, fb.detections, ("keypoints", "confidences", "boxes", "scores"))):
            assert (ga is None) == (gb is None)
            if ga is not None:
                for f in fields:
                    assert _same(getattr(ga, f), getattr(gb, f)), f"frame {fa.index}: {f} differs"
