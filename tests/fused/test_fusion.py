import numpy as np
import pytest

from pedenv.fused.cue import CueEstimate
from pedenv.fused.fusion import chi2_quantile_2dof, fuse_cues


def cue(name, pos, cov, valid=True):
    return CueEstimate(name, np.array([pos], float), np.array([cov], float), np.array([valid]),
                       np.array(["" if valid else "declined"], object))


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
    c = CueEstimate("ground", np.array([[np.nan, 1.0]]), np.array([np.eye(2)]), np.array([True]), np.array([""], object))
    assert not c.valid[0] and c.reasons[0] == "degenerate" and np.isfinite(c.positions).all()
