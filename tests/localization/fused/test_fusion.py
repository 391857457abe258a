import numpy as np
import pytest

from pedenv.localization.fused.cue import REASON_CODE, CueEstimate
from pedenv.localization.fused.fusion import chi2_quantile_2dof, fuse_cues
from pedenv.localization.fused.sources import CueSources


def cue(name, pos, cov, valid=True, bias=None):
    bias = np.zeros((2, 2)) if bias is None else bias
    return CueEstimate(name, np.array([pos], float), np.array([cov], float), np.array([bias], float),
                       np.array([valid]), np.array([0 if valid else REASON_CODE["no-keypoints"]]))


def test_two_independent_gaussians_by_hand():
    # x-variances 1 and 4: weights 0.8 and 0.2; y-variances 4 and 1: weights 0.2 and 0.8
    a = cue("height", [10.0, 0.0], [[1.0, 0.0], [0.0, 4.0]])
    b = cue("ground", [12.0, 1.0], [[4.0, 0.0], [0.0, 1.0]])
    fused = fuse_cues([a, b], 0.999)
    np.testing.assert_allclose(fused.positions[0], [10.4, 0.8])
    np.testing.assert_allclose(fused.covariances[0], [[0.8, 0.0], [0.0, 0.8]])
    assert fused.used[0].tolist() == [True, True]


def test_correlated_covariances_by_hand():
    s1 = np.array([[2.0, 1.0], [1.0, 2.0]])
    s2 = np.array([[1.0, 0.0], [0.0, 1.0]])
    fused = fuse_cues([cue("height", [0.0, 0.0], s1), cue("ground", [1.0, 1.0], s2)], 0.999)
    info = np.linalg.inv(s1) + np.linalg.inv(s2)
    expected_cov = np.linalg.inv(info)
    np.testing.assert_allclose(fused.covariances[0], expected_cov)
    np.testing.assert_allclose(fused.positions[0], expected_cov @ (np.linalg.inv(s2) @ [1.0, 1.0]))


def test_a_bad_cue_is_outvoted_not_averaged():
    good1 = cue("height", [20.0, 0.0], np.diag([1.0, 0.1]))
    good2 = cue("triangulation", [20.5, 0.1], np.diag([1.0, 0.1]))
    bad = cue("ground", [35.0, 0.0], np.diag([1.0, 0.1]))
    fused = fuse_cues([bad, good1, good2], 0.999)
    assert fused.used[0].tolist() == [False, True, True]
    assert fused.outvoted[0].tolist() == [True, False, False]
    assert fused.positions[0, 0] == pytest.approx(20.25)


def test_two_disagreeing_cues_keep_the_trusted_one():
    fused = fuse_cues([cue("ground", [35.0, 0.0], np.eye(2)), cue("height", [20.0, 0.0], np.eye(2))], 0.999)
    assert fused.used[0].tolist() == [False, True]
    assert fused.positions[0, 0] == pytest.approx(20.0)


def test_declined_cues_are_ignored_and_none_left_is_invalid():
    fused = fuse_cues([cue("ground", [0.0, 0.0], np.eye(2), valid=False), cue("height", [5.0, 1.0], np.eye(2))], 0.999)
    np.testing.assert_allclose(fused.positions[0], [5.0, 1.0])
    fused = fuse_cues([cue("ground", [0.0, 0.0], np.eye(2), valid=False)], 0.999)
    assert not fused.valid[0] and np.isfinite(fused.positions).all() and np.isfinite(fused.covariances).all()


def test_chi2_quantile():
    assert chi2_quantile_2dof(0.95) == pytest.approx(5.991, abs=1e-3)


def test_cue_with_nan_declines_as_degenerate():
    bad = cue("ground", [np.nan, 1.0], np.eye(2))
    fused = fuse_cues([bad, cue("height", [5.0, 1.0], np.eye(2))], 0.999)
    assert fused.degenerate[0].tolist() == [True, False] and not fused.used[0, 0]
    assert np.isfinite(fused.positions).all()
    assert CueSources.of([bad, cue("height", [5.0, 1.0], np.eye(2))], fused, ~fused.valid).spell()[0] == \
        "height;ground:degenerate"


def test_the_fused_covariance_splits_into_frame_and_per_person_parts():
    # S_c = F_c + B_c; F = S (sum S_c^-1 F_c S_c^-1) S and B = S - F
    f1, b1 = np.diag([1.0, 2.0]), np.diag([3.0, 0.5])
    f2, b2 = np.array([[2.0, 0.5], [0.5, 1.0]]), np.diag([0.0, 1.0])
    fused = fuse_cues([cue("height", [0.0, 0.0], f1, bias=b1), cue("ground", [0.5, 0.2], f2, bias=b2)], 0.999)
    i1, i2 = np.linalg.inv(f1 + b1), np.linalg.inv(f2 + b2)
    s = np.linalg.inv(i1 + i2)
    frame = s @ (i1 @ f1 @ i1 + i2 @ f2 @ i2) @ s
    np.testing.assert_allclose(fused.covariances[0], frame)
    np.testing.assert_allclose(fused.bias_covariances[0], s - frame, atol=1e-12)


def test_sources_name_used_cues_then_why_not_the_others():
    cues = [cue("ground", [0.0, 0.0], np.eye(2), valid=False), cue("height", [5.0, 1.0], np.eye(2))]
    fused = fuse_cues(cues, 0.999)
    assert CueSources.of(cues, fused, np.array([False])).spell()[0] == "height;ground:no-keypoints"
    assert CueSources.of(cues, fused, np.array([True])).spell()[0] == "boxheight;ground:no-keypoints"


def test_bearing_floor_keeps_the_sharpest_cues_sideways_variance():
    # two cues 10 m ahead (camera at the origin, ray along x): sideways (y) variances 0.04 and
    # 0.09 m^2 share the person's bearing error, so the fusion keeps 0.04, not 0.028
    a = cue("height", [10.0, 0.0], [[1.0, 0.0], [0.0, 0.03]], bias=np.diag([0.5, 0.01]))
    b = cue("ground", [10.2, 0.0], [[0.5, 0.0], [0.0, 0.09]])
    independent = fuse_cues([a, b], 0.999)
    floored = fuse_cues([a, b], 0.999, origin=np.zeros(2))
    total = lambda f: f.covariances[0] + f.bias_covariances[0]  # noqa: E731
    assert total(independent)[1, 1] < 0.03
    assert total(floored)[1, 1] == pytest.approx(0.04)
    assert floored.covariances[0, 1, 1] == pytest.approx(0.03)
    assert floored.bias_covariances[0, 1, 1] == pytest.approx(0.01)
    np.testing.assert_allclose(total(floored)[0, 0], total(independent)[0, 0])  # along the ray: independent cues
    np.testing.assert_allclose(floored.positions, independent.positions)
