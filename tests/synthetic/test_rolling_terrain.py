"""Rolling terrain: flat plane, grade bound, analytic gradient."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.synthetic.terrain import Terrain, random_terrain


def test_flat_terrain_is_the_plane_z_0():
    flat = Terrain.flat()
    xy = np.random.default_rng(0).uniform(-500, 500, (50, 2))
    assert flat.is_flat and flat.max_grade == 0.0
    assert np.array_equal(flat.height(xy), np.zeros(50)) and np.array_equal(flat.gradient(xy), np.zeros((50, 2)))


def test_single_wave_height_and_grade_by_hand():
    # z = 2 sin(2 pi x / 200): peak 2 m at x = 50 m, grade 2 * 2 pi / 200 = 6.28 % at x = 0
    wave = Terrain(np.array([2.0]), np.array([[2 * np.pi / 200, 0.0]]), np.zeros(1))
    assert wave.height(np.array([50.0, 7.0])) == pytest.approx(2.0)
    assert wave.gradient(np.array([0.0, 0.0])) == pytest.approx([0.0628, 0.0], abs=1e-4)
    assert wave.max_grade == pytest.approx(0.0628, abs=1e-4)


@pytest.mark.parametrize("seed", range(6))
def test_random_terrain_grade_stays_below_5_percent(seed):
    terrain = random_terrain(np.random.default_rng(seed))
    xy = np.stack(np.meshgrid(np.arange(-400, 400, 4.0), np.arange(-400, 400, 4.0)), axis=-1)
    grade = np.linalg.norm(terrain.gradient(xy), axis=-1)
    assert terrain.max_grade <= 0.05 and grade.max() <= 0.05
    assert grade.max() > 0.02  # hilly, not flat
    # the analytic gradient matches finite differences
    h = 1e-3
    fd = np.stack([(terrain.height(xy + [h, 0]) - terrain.height(xy - [h, 0])) / (2 * h),
                   (terrain.height(xy + [0, h]) - terrain.height(xy - [0, h])) / (2 * h)], axis=-1)
    np.testing.assert_allclose(terrain.gradient(xy), fd, atol=1e-7)


@pytest.mark.parametrize("kwargs", [{"max_grade": -0.01}, {"max_grade": 0.5}, {"components": 0}])
def test_random_terrain_rejects_bad_options(kwargs):
    with pytest.raises(ValueError):
        random_terrain(np.random.default_rng(0), **kwargs)
