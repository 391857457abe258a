import numpy as np
import pytest

from pedenv import kalman


@pytest.mark.parametrize("dt, std", [(0.1, 1.0), (1 / 12, 0.3), (0.5, 2.0)])
def test_q_symmetric_positive_semidefinite(dt, std):
    F, Q = kalman.transition(dt, std)
    np.testing.assert_allclose(Q, Q.T)
    assert np.linalg.eigvalsh(Q).min() >= -1e-12
    # white-noise acceleration: var(x) = dt^4/4 * sigma^2, cov(x, vx) = dt^3/2 * sigma^2
    assert Q[0, 0] == pytest.approx(dt**4 / 4 * std**2)
    assert Q[0, 1] == pytest.approx(dt**3 / 2 * std**2)
    assert F[0, 1] == dt and F[2, 3] == dt and F[0, 2] == 0


def test_filter_learns_a_constant_velocity():
    rng = np.random.default_rng(0)
    x, P = kalman.initial_state(np.array([[0.0, 0.0]]), np.array([np.eye(2) * 0.25]), 2.0)
    F, Q = kalman.transition(0.1, 0.5)
    for i in range(1, 80):
        x, P = kalman.predict(x, P, F, Q)
        z = np.array([[1.2 * 0.1 * i, -0.5 * 0.1 * i]]) + rng.normal(0, 0.5, (1, 2))
        x, P = kalman.update(x, P, z, np.array([0.25]))
    assert x[0, 1] == pytest.approx(1.2, abs=0.3) and x[0, 3] == pytest.approx(-0.5, abs=0.3)
    np.testing.assert_allclose(P[0], P[0].T, atol=1e-12)
    assert np.linalg.eigvalsh(P[0]).min() > 0


def test_innovation_distance_hand_checked():
    x = np.array([[1.0, 0.0, 2.0, 0.0]])
    P = np.zeros((1, 4, 4))
    P[0, 0, 0] = P[0, 2, 2] = 1.0
    r = np.array([np.eye(2)])
    # innovation (2, 2), S = 2 I: d^2 = (4 + 4) / 2
    assert kalman.innovation_distance(x, P, np.array([[3.0, 4.0]]), r)[0] == pytest.approx(4.0)


@pytest.mark.parametrize("dt, std", [(0.1, 1.0), (1 / 12, 0.3), (0.5, 2.0)])
def test_q_equals_filterpys_white_noise(dt, std):
    from filterpy.common import Q_discrete_white_noise

    _, Q = kalman.transition(dt, std)
    want = Q_discrete_white_noise(dim=2, dt=dt, var=std**2, block_size=2, order_by_dim=True)
    np.testing.assert_allclose(Q, want, rtol=1e-12, atol=1e-15)


def test_batched_filter_equals_filterpy_track_by_track():
    """Five tracks with different covariances through predict/update, each against its own
    filterpy.kalman.KalmanFilter (same F, Q, H, R)."""
    from filterpy.kalman import KalmanFilter

    rng = np.random.default_rng(3)
    n = 5
    z0 = rng.normal(0, 10, (n, 2))
    r0 = np.array([np.diag(rng.uniform(0.1, 2.0, 2)) for _ in range(n)])
    x, P = kalman.initial_state(z0, r0, 1.5)
    filters = []
    for i in range(n):
        kf = KalmanFilter(dim_x=4, dim_z=2)
        kf.x, kf.P, kf.H = x[i].copy(), P[i].copy(), kalman.H.copy()
        filters.append(kf)
    for step in range(12):
        dt = 0.05 + 0.01 * step
        F, Q = kalman.transition(dt, 0.8)
        x, P = kalman.predict(x, P, F, Q)
        a = rng.normal(0, 1, (n, 2, 2))
        R = a @ np.transpose(a, (0, 2, 1)) + 0.1 * np.eye(2)  # full, correlated covariances
        z = x @ kalman.H.T + rng.normal(0, 1, (n, 2))
        x, P = kalman.update(x, P, z, R)
        for i, kf in enumerate(filters):
            kf.F, kf.Q = F, Q
            kf.predict()
            kf.update(z[i], R=R[i])
            np.testing.assert_allclose(x[i], kf.x, rtol=1e-10, atol=1e-10)
            np.testing.assert_allclose(P[i], kf.P, rtol=1e-9, atol=1e-10)


def test_correct_leaves_tracks_with_a_non_finite_measurement_alone():
    """Issue 10.2: a NaN or inf measurement is no measurement; nothing non-finite enters the state."""
    from pedenv.config import KalmanConfig

    x, P = kalman.initial_state(np.array([[5.0, 1.0], [7.0, 2.0], [0.0, 0.0]]), np.tile(np.eye(2), (3, 1, 1)), 2.0)
    started = np.array([True, True, False])
    z = np.array([[5.5, 1.0], [np.nan, 2.0], [np.inf, 0.0]])
    r = np.tile(np.eye(2) * 0.25, (3, 1, 1))
    x2, P2, measured = kalman.correct(x, P, started, z, r, r, KalmanConfig(restart_gate=25.0))
    assert measured.tolist() == [True, False, False]
    assert np.isfinite(x2).all() and np.isfinite(P2).all()
    np.testing.assert_array_equal(x2[1:], x[1:])
    assert 5.0 < x2[0, 0] < 5.5


def test_measurement_exact_along_the_direction_the_state_is_exact_stays_finite():
    """The state and the measurement each certain along the same direction (a box range taken
    as exact, twice): the innovation covariance is singular there. Seen on a real recording
    as a jump of 2.4 m and 37 m/s in one frame; the measurement's variance is floored instead."""
    along = np.array([1.0, -1.73]) / np.hypot(1.0, 1.73)
    across = np.array([-along[1], along[0]])
    x = np.array([[3.888, 1.686, 1.235, 2.344]])
    P = np.zeros((1, 4, 4))
    P[0][np.ix_([0, 2], [0, 2])] = 0.2 * np.outer(across, across)  # certain along ``along``
    P[0][np.ix_([1, 3], [1, 3])] = 2.0 * np.eye(2)
    r = np.array([0.25 * np.outer(across, across)])
    z = np.array([[3.179, 1.144]])
    new, P_new = kalman.update(x, P, z, r)
    assert np.isfinite(new).all() and np.isfinite(P_new).all()
    position = new[0, [0, 2]]
    assert np.linalg.norm(position - z[0]) < np.linalg.norm(x[0, [0, 2]] - z[0])  # between prior and measurement
    assert np.abs(new[0, [1, 3]]).max() < 5.0  # the velocity is left about where it was
    assert np.linalg.eigvalsh(P_new[0]).min() > -1e-9
    r_floor = kalman.floor_variance(r)
    assert np.linalg.eigvalsh(r_floor[0]).min() == pytest.approx(kalman.MIN_MEASUREMENT_VARIANCE)
    ordinary = np.array([np.diag([0.04, 0.01])])
    assert kalman.floor_variance(ordinary) is ordinary  # a proper covariance is left as it is
