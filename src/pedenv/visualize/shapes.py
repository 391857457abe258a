"""Shapes the viewers draw: covariance ellipses and the camera's field of view on the ground."""

from __future__ import annotations

import numpy as np


def covariance_ellipses(centers: np.ndarray, covariances: np.ndarray, sigma: float = 2.0,
                        segments: int = 36) -> np.ndarray:
    """Closed outlines of the ``sigma`` ellipses of 2D Gaussians.

    centers: (N, 2) metres; covariances: (N, 2, 2) m^2, symmetric positive semi-definite.
    Returns (N, segments + 1, 2) metres, in the frame of ``centers`` (first point repeated last).
    """
    centers = np.asarray(centers, float).reshape(-1, 2)
    cov = np.asarray(covariances, float).reshape(-1, 2, 2)
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.transpose(0, 2, 1)))
    radii = sigma * np.sqrt(np.clip(values, 0.0, None))  # (N, 2)
    angle = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    unit = np.stack([np.cos(angle), np.sin(angle)], axis=1)  # (S+1, 2)
    return centers[:, None, :] + np.einsum("nij,sj->nsi", vectors * radii[:, None, :], unit)


def field_of_view(hfov: float, reach: float) -> np.ndarray:
    """The camera's horizontal field of view as a ground triangle (3, 2): apex, left edge, right edge.

    Vehicle frame (x forward, y left), metres; ``hfov`` radians, ``reach`` metres along x.
    """
    half = np.tan(hfov / 2.0) * reach
    return np.array([[0.0, 0.0], [reach, half], [reach, -half]])
