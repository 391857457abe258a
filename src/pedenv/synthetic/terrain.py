"""Rolling terrain of the synthetic scenes: a sum of a few long plane waves.

``z(x, y) = sum_i A_i sin(k_i . (x, y) + phi_i)``, world frame, metres. The grade
``|grad z|`` is at most ``sum_i A_i |k_i|``, which :func:`random_terrain` keeps below its
``max_grade`` by construction; the flat terrain has no waves and is z = 0 everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.validation import check_count, check_number


@dataclass(frozen=True)
class Terrain:
    """A smooth height field.

    amplitudes: (M,) float, metres.
    wavevectors: (M, 2) float, radians per metre, world x-y.
    phases: (M,) float, radians.
    """

    amplitudes: np.ndarray
    wavevectors: np.ndarray
    phases: np.ndarray

    @classmethod
    def flat(cls) -> Terrain:
        """The plane z = 0."""
        return cls(np.zeros(0), np.zeros((0, 2)), np.zeros(0))

    @property
    def is_flat(self) -> bool:
        return self.amplitudes.size == 0 or not np.any(self.amplitudes)

    @property
    def max_grade(self) -> float:
        """Upper bound of the grade ``|grad z|`` anywhere (dimensionless, 0.05 = 5 %)."""
        return float(np.sum(np.abs(self.amplitudes) * np.linalg.norm(self.wavevectors, axis=1)))

    def height(self, xy: np.ndarray) -> np.ndarray:
        """Terrain height: xy (..., 2) world frame, metres -> (...,) metres."""
        xy = np.asarray(xy, float)
        if self.is_flat:
            return np.zeros(xy.shape[:-1])
        arg = xy @ self.wavevectors.T + self.phases  # (..., M)
        return np.sin(arg) @ self.amplitudes

    def gradient(self, xy: np.ndarray) -> np.ndarray:
        """(dz/dx, dz/dy): xy (..., 2) world frame, metres -> (..., 2) dimensionless."""
        xy = np.asarray(xy, float)
        if self.is_flat:
            return np.zeros(xy.shape)
        arg = xy @ self.wavevectors.T + self.phases
        return (np.cos(arg) * self.amplitudes) @ self.wavevectors


def random_terrain(rng: np.random.Generator, *, max_grade: float = 0.05, components: int = 3,
                   wavelength_range_m: tuple[float, float] = (80.0, 300.0)) -> Terrain:
    """Rolling hills whose grade never exceeds ``max_grade`` (0.05 = 5 %).

    Each of ``components`` waves gets a random direction, a wavelength drawn from
    ``wavelength_range_m`` and a share of the grade budget; its amplitude is that share
    divided by its wavenumber, so the summed bound equals ``0.98 * max_grade``.
    """
    check_number("max_grade", max_grade, 0, 0.3)
    check_count("components", components, 1, 100)
    wavelengths = rng.uniform(*wavelength_range_m, components)
    angles = rng.uniform(0.0, 2.0 * np.pi, components)
    k = 2.0 * np.pi / wavelengths
    wavevectors = np.stack([k * np.cos(angles), k * np.sin(angles)], axis=1)
    shares = rng.dirichlet(np.full(components, 2.0)) * 0.98 * max_grade
    return Terrain(shares / k, wavevectors, rng.uniform(0.0, 2.0 * np.pi, components))
