"""pedenv bench's synthetic frames: only what the camera sees, so a long run never feeds the
model people behind it (which the model refuses as absurd pixels)."""

import numpy as np
import pytest

from pedenv.apps.bench import bench_core, bench_frames


def test_bench_frames_hold_only_people_in_view():
    frames = bench_frames(100, n_frames=100)
    counts = [len(f.detections) for f in frames]
    assert 80 <= min(counts) < max(counts) <= 100  # measured 94 in view at first, 84 after 10 s
    for f in frames:
        u = f.detections.keypoints[..., 0]
        assert np.all(u.max(axis=1) > 0) and np.all(u.min(axis=1) < f.camera.width)


def test_bench_core_runs_the_default_hundred_frames():
    rows = bench_core(pedestrian_counts=(10,), n_frames=100)
    assert rows[0]["pedestrians"] == 10 and rows[0]["tracking_per_frame"] > 0


@pytest.mark.onnx_model
@pytest.mark.slow
def test_detection_modes_side_by_side_with_their_cost():
    from pedenv.apps.bench import bench_detection_modes, format_detection_modes

    rows = bench_detection_modes(repeats=1)
    fast, far, stream = rows
    assert (fast["mode"], far["mode"], stream["mode"]) == ("fast", "far", "stream")
    assert fast["passes"] == 1 and fast["units"] == pytest.approx(1.0)
    # far on a level camera 1.5 m high: the whole frame, the x1 band and the x2 band
    assert far["passes"] == 3 and 3.0 < far["units"] < 7.0
    # stream after its cold start: the whole frame and band tiles in rotation, within its budget of 3 units
    assert 1.0 < stream["units"] <= 3.0 + 1.0
    assert all(r["ms"] > 0 and r["cpus"] >= 1 and "recall" not in r for r in rows)
    assert format_detection_modes(rows).row_count == 3
