import numpy as np

from pedenv.localization.fused.cue import REASON_CODE, CueEstimate
from pedenv.localization.fused.fusion import fuse_cues
from pedenv.localization.fused.sources import CueSources


def cues(positions, valid, reasons):
    """Cues ``ground`` and ``height`` of N pedestrians: positions (N, 2, 2), valid (N, 2), reasons (N, 2) names."""
    p, v = np.asarray(positions, float), np.asarray(valid)
    codes = np.array([[REASON_CODE[r] for r in row] for row in reasons], np.int64).reshape(len(p), 2)
    eye = np.broadcast_to(np.eye(2), (len(p), 2, 2))
    return [CueEstimate(name, p[:, c], eye, np.zeros_like(eye), v[:, c], codes[:, c])
            for c, name in enumerate(("ground", "height"))]


def test_each_pedestrian_spelled_from_its_flags():
    # both agree; one declined; far apart (between two, the later in the trust order, ground, goes); none
    q = cues([[[10, 0], [10.2, 0]], [[0, 0], [20, 0]], [[30, 0], [5, 0]], [[0, 0], [0, 0]]],
             [[True, True], [False, True], [True, True], [False, False]],
             [["", ""], ["beyond-range", ""], ["", ""], ["no-ankles", "no-keypoints"]])
    fused = fuse_cues(q, 0.999)
    got = CueSources.of(q, fused, ~fused.valid).spell()
    assert got.tolist() == ["ground+height", "height;ground:beyond-range", "height;ground:outvoted",
                            "box;ground:no-ankles;height:no-keypoints"]


def test_no_pedestrians_spell_nothing():
    q = cues(np.zeros((0, 2, 2)), np.zeros((0, 2), bool), [])
    fused = fuse_cues(q, 0.999)
    assert len(CueSources.of(q, fused, ~fused.valid).spell()) == 0
