"""What every cue returns, and the geometry the cues share.

A cue estimates the horizontal position of each pedestrian's ground point (world x-y)
with a 2x2 covariance, or declines for that pedestrian with a short reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.errors import check_array


@dataclass(frozen=True)
class CueEstimate:
    """One cue's estimate for the N pedestrians of a frame.

    name: the cue (``ground``, ``triangulation``, ``height``).
    positions: (N, 2) float, world x-y, metres; 0 where the cue declined.
    covariances: (N, 2, 2) float, m^2; identity where the cue declined.
    valid: (N,) bool, the cue has an estimate.
    reasons: (N,) str, why the cue declined (empty where valid), e.g. ``no-ankles``.
    """

    name: str
    positions: np.ndarray
    covariances: np.ndarray
    valid: np.ndarray
    reasons: np.ndarray

    def __post_init__(self) -> None:
        pos = check_array(f"{self.name} positions", self.positions, (None, 2), finite=False)
        n = pos.shape[0]
        cov = check_array(f"{self.name} covariances", self.covariances, (n, 2, 2), finite=False)
        valid = check_array(f"{self.name} valid", self.valid, (n,), dtype=bool)
        # a cue whose numbers are not finite declines: no NaN or inf reaches the fusion
        with np.errstate(invalid="ignore"):
            det = cov[:, 0, 0] * cov[:, 1, 1] - cov[:, 0, 1] * cov[:, 1, 0]
            finite = np.isfinite(pos).all(axis=1) & np.isfinite(cov).all(axis=(1, 2)) & (det > 0) & (cov[:, 0, 0] > 0)
        reasons = np.asarray(self.reasons, dtype=object)
        reasons = np.where(valid & ~finite, "degenerate", reasons)
        valid = valid & finite
        object.__setattr__(self, "positions", np.where(valid[:, None], pos, 0.0))
        object.__setattr__(self, "covariances", np.where(valid[:, None, None], cov, np.eye(2)))
        object.__setattr__(self, "valid", valid)
        object.__setattr__(self, "reasons", np.where(valid, "", reasons))

    def __len__(self) -> int:
        return self.positions.shape[0]

    @classmethod
    def declined(cls, name: str, n: int, reason: str) -> "CueEstimate":
        """The cue declines for all N pedestrians with one reason."""
        return cls(name, np.zeros((n, 2)), np.tile(np.eye(2), (n, 1, 1)), np.zeros(n, bool), np.full(n, reason, object))


def first_reason(conditions: list[tuple[np.ndarray, str]], n: int) -> np.ndarray:
    """(N,) str: the reason of the first condition (in list order) that holds; empty if none.

    conditions: ``[(mask (N,) bool, reason), ...]``.
    """
    out = np.full(n, "", dtype=object)
    for mask, reason in reversed(conditions):
        out = np.where(mask, reason, out)
    return out


def horizontal_bearing(rays: np.ndarray) -> np.ndarray:
    """Unit horizontal direction (..., 2) of world rays (..., 3); +x where a ray is vertical."""
    xy = rays[..., :2]
    norm = np.linalg.norm(xy, axis=-1, keepdims=True)
    return np.where(norm > 1e-12, xy / np.maximum(norm, 1e-12), np.array([1.0, 0.0]))


def range_bearing_covariance(bearing: np.ndarray, range_var: np.ndarray, across_var: np.ndarray) -> np.ndarray:
    """Covariance (N, 2, 2) m^2 with ``range_var`` (N,) along ``bearing`` (N, 2) and
    ``across_var`` (N,) across it: wide along the viewing ray, tight across it."""
    b = bearing
    perp = np.stack([-b[:, 1], b[:, 0]], axis=1)
    return (range_var[:, None, None] * np.einsum("ni,nj->nij", b, b)
            + across_var[:, None, None] * np.einsum("ni,nj->nij", perp, perp))


def across_variance(ranges: np.ndarray, focal_px: float, pixel_std: float, lateral_std_m: float) -> np.ndarray:
    """Variance (N,) m^2 across the ray at horizontal ``ranges`` (N,) metres: the pixel noise
    seen at that range plus the body's own spread ``lateral_std_m``."""
    return (ranges * pixel_std / focal_px) ** 2 + lateral_std_m**2


def keypoint_usable(keypoints: np.ndarray, confidences: np.ndarray, width: int, height: int,
                    min_confidence: float = 0.0) -> np.ndarray:
    """(N, 17) bool: keypoints seen (confidence > 0 and >= ``min_confidence``), finite and
    inside the image. keypoints: (N, 17, 2) pixels; confidences: (N, 17).
    """
    u, v = keypoints[..., 0], keypoints[..., 1]
    with np.errstate(invalid="ignore"):
        inside = (u >= 0) & (u <= width - 1) & (v >= 0) & (v <= height - 1)
    return (confidences > 0) & (confidences >= min_confidence) & np.isfinite(keypoints).all(axis=-1) & inside


#: Two seen ankles whose heights differ by more than this many pixel-noise sigmas plus
#: :data:`LIFTED_ANKLE_EXTENT` of the skeleton's height: the higher one is the swing foot
#: and is left out; closer, both stand (or noise decides) and both are used.
LIFTED_ANKLE_SIGMA = 2.0
#: Share of the skeleton's vertical extent two standing ankles may differ by (stride on a
#: slope, a foot rolling over); a swing foot rises up to ~0.15 of body height.
LIFTED_ANKLE_EXTENT = 0.01


#: Left/right keypoint pairs at the same height of an upright body: their elevation
#: difference is the keypoint noise (eyes, ears, shoulders, hips).
LEVEL_PAIRS = np.array([[1, 2], [3, 4], [5, 6], [11, 12]])
#: Weight (in pairs) of the configured pixel noise against the pairs' own evidence.
NOISE_PRIOR_PAIRS = 0.1


def observed_angle_std(usable: np.ndarray, tangents: np.ndarray, angle_std: float) -> np.ndarray:
    """(N,) each skeleton's keypoint noise (radians) from its level pairs' elevation
    differences, shrunk towards the configured ``angle_std`` (pixel noise / focal length).

    usable: (N, 17) bool. tangents: (N, 17) tan of each keypoint ray's elevation.
    """
    both = usable[:, LEVEL_PAIRS[:, 0]] & usable[:, LEVEL_PAIRS[:, 1]]
    diff = np.where(both, tangents[:, LEVEL_PAIRS[:, 0]] - tangents[:, LEVEL_PAIRS[:, 1]], 0.0)
    return np.sqrt((0.5 * (diff**2).sum(1) + NOISE_PRIOR_PAIRS * angle_std**2) / (both.sum(1) + NOISE_PRIOR_PAIRS))


def stance_ankle(usable: np.ndarray, rays: np.ndarray, ankles: tuple[int, int], angle_std: float):
    """Which ankles stand on the ground. Of two seen ankles whose elevations differ by
    more than :data:`LIFTED_ANKLE_SIGMA` times the noise of their difference plus
    :data:`LIFTED_ANKLE_EXTENT` of the skeleton's extent, the higher is the swing foot
    (lifted up to ~0.15 of body height) and is left out; otherwise both are used.

    usable: (N, 17) bool. rays: (N, 17, 3) unit, world. ankles: the two ankle indices.
    angle_std: pixel noise / focal length (radians), the prior of each skeleton's own
    noise (:func:`observed_angle_std`). Returns ``(use (N, 2) bool, lone (N,) bool)``: the
    ankles to use, and where only one ankle was seen (it may be lifted).
    """
    a = list(ankles)
    tan = rays[..., 2] / np.maximum(np.linalg.norm(rays[..., :2], axis=-1), 1e-9)  # (N, 17)
    angle_std = observed_angle_std(usable, tan, angle_std)
    extent = np.where(usable, tan, -np.inf).max(axis=1) - np.where(usable, tan, np.inf).min(axis=1)
    seen, z = usable[:, a], tan[:, a]
    both = seen.all(axis=1)
    limit = LIFTED_ANKLE_SIGMA * np.sqrt(2.0) * angle_std + LIFTED_ANKLE_EXTENT * np.where(both, extent, 0.0)
    lifted = both & (np.abs(z[:, 0] - z[:, 1]) > limit)
    lower_first = z[:, 0] <= z[:, 1]
    use = np.where(lifted[:, None], np.column_stack([lower_first, ~lower_first]), seen)
    return use, seen.any(axis=1) & ~both


def inverse_2x2(a: np.ndarray) -> np.ndarray:
    """Closed-form inverse of (..., 2, 2) matrices (cheaper than ``np.linalg.inv`` on small batches)."""
    det = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    adj = np.stack([np.stack([a[..., 1, 1], -a[..., 0, 1]], -1), np.stack([-a[..., 1, 0], a[..., 0, 0]], -1)], -2)
    return adj / det[..., None, None]


def inverse_3x3_symmetric(a: np.ndarray):
    """Closed-form inverse of symmetric (..., 3, 3) matrices and their determinants."""
    c00 = a[..., 1, 1] * a[..., 2, 2] - a[..., 1, 2] ** 2
    c01 = a[..., 0, 2] * a[..., 1, 2] - a[..., 0, 1] * a[..., 2, 2]
    c02 = a[..., 0, 1] * a[..., 1, 2] - a[..., 0, 2] * a[..., 1, 1]
    c11 = a[..., 0, 0] * a[..., 2, 2] - a[..., 0, 2] ** 2
    c12 = a[..., 0, 2] * a[..., 0, 1] - a[..., 0, 0] * a[..., 1, 2]
    c22 = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] ** 2
    det = a[..., 0, 0] * c00 + a[..., 0, 1] * c01 + a[..., 0, 2] * c02
    adj = np.stack([np.stack([c00, c01, c02], -1), np.stack([c01, c11, c12], -1), np.stack([c02, c12, c22], -1)], -2)
    return adj / np.where(det == 0, 1.0, det)[..., None, None], det
