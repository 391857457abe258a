import numpy as np

from pedenv.localization.fused.cue import IDENTITY, Sym2


def random_spd(rng, shape):
    a = rng.normal(size=shape + (2, 2))
    return a @ np.swapaxes(a, -1, -2) + 0.1 * np.eye(2)


def test_sym2_algebra_matches_the_matrices():
    rng = np.random.default_rng(0)
    m, f = random_spd(rng, (4, 3)), random_spd(rng, (4, 3))
    a, b = Sym2.of(m), Sym2.of(f)
    np.testing.assert_allclose(a.matrices(), m)
    np.testing.assert_allclose(a.inverse().matrices(), np.linalg.inv(m))
    np.testing.assert_allclose((a + b).matrices(), m + f)
    np.testing.assert_allclose((a - b).matrices(), m - f)
    np.testing.assert_allclose(a.sandwich(b).matrices(), m @ f @ m)
    np.testing.assert_allclose(a.sum().matrices(), m.sum(axis=1))
    v = rng.normal(size=(4, 3, 2))
    np.testing.assert_allclose(np.stack(a.times(v[..., 0], v[..., 1]), -1), (m @ v[..., None])[..., 0])
    np.testing.assert_allclose(a.quadratic(v[..., 0], v[..., 1]), np.einsum("nci,ncij,ncj->nc", v, m, v))
    mask = rng.random((4, 3)) > 0.5
    np.testing.assert_allclose(a.where(mask, IDENTITY).matrices(), np.where(mask[..., None, None], m, np.eye(2)))
