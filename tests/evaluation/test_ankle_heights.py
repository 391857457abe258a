"""The ankle keypoint's height above the 3D truth's ground (:mod:`pedenv.evaluation.person_offsets`,
printed by benchmarks/ankle_heights.py),
which sets ``fused.ankle_keypoint_offset_m``, on constructed detections."""

import numpy as np
import pytest

#: A KITTI-like camera: focal 721.5 px, principal row 172.9 px.
K = np.array([[721.5, 0.0, 609.6], [0.0, 721.5, 172.9], [0.0, 0.0, 1.0]])


def detection(ankle_rows, confidence=0.9, box=(570.0, 50.0, 650.0, 300.0), score=0.8) -> dict:
    kp = np.zeros((1, 17, 2))
    kp[0, :, 0] = 610.0
    kp[0, 15, 1], kp[0, 16, 1] = ankle_rows
    conf = np.full((1, 17), 0.9)
    conf[0, 15:17] = confidence
    return {"keypoints": kp, "confidences": conf, "boxes": np.array([box]), "scores": np.array([score])}


def row_at(height_m: float, bottom_y: float = 1.65, depth: float = 10.0) -> float:
    """The image row of a point ``height_m`` above a box bottom at camera y ``bottom_y`` and depth ``depth``."""
    return K[1, 2] + K[1, 1] * (bottom_y - height_m) / depth


def test_the_lower_ankle_is_measured_above_the_box_bottom():
    from pedenv.evaluation.person_offsets import lower_ankle_heights

    truth = np.array([[572.0, 52.0, 648.0, 298.0]])
    bottoms = np.array([[0.0, 1.65, 10.0]])  # camera frame, y down: 1.65 m below the camera, 10 m ahead
    det = detection((row_at(0.118), row_at(0.30)))  # the right ankle swings 0.30 m up
    found = lower_ankle_heights(det, truth, bottoms, K, np.array([True]))
    assert found == {0: pytest.approx(0.118, abs=1e-9)}


@pytest.mark.parametrize("change", ["unsure ankles", "not counted", "no overlap", "low score"])
def test_persons_the_measure_leaves_out(change):
    from pedenv.evaluation.person_offsets import lower_ankle_heights

    truth = np.array([[572.0, 52.0, 648.0, 298.0]])
    bottoms = np.array([[0.0, 1.65, 10.0]])
    rows = (row_at(0.1), row_at(0.1))
    det = {"unsure ankles": detection(rows, confidence=0.4), "no overlap": detection(rows, box=(0, 0, 50, 100)),
           "low score": detection(rows, score=0.2)}.get(change, detection(rows))
    counted = np.array([change != "not counted"])
    assert lower_ankle_heights(det, truth, bottoms, K, counted) == {}
