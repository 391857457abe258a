"""Information-weighted fusion of the cues, with a chi-square gate against a bad cue.

For cue estimates ``(mu_c, S_c)`` the fused estimate is ``S = (sum S_c^-1)^-1``,
``mu = S sum S_c^-1 mu_c``. Before that, each cue is compared with the fusion of the
others: ``d^2 = (mu_c - mu_rest)^T (S_c + S_rest)^-1 (mu_c - mu_rest)``. While the worst
``d^2`` exceeds the chi-square quantile (2 dof) that cue is dropped, so a bad cue is
outvoted, not averaged in. Between two cues only, the one later in the trust order is
dropped (the height cue is trusted most: terrain and a walking person bias the others).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.fused.cue import CueEstimate, inverse_2x2

#: Which cue to keep when only two disagree: earlier in this tuple wins.
TRUST_ORDER = ("height", "triangulation", "ground")


def chi2_quantile_2dof(probability: float) -> float:
    """The chi-square quantile with 2 degrees of freedom: ``-2 ln(1 - p)``."""
    return float(-2.0 * np.log1p(-probability))


@dataclass(frozen=True)
class Fused:
    """The fused estimate of N pedestrians.

    positions: (N, 2) world x-y, metres. covariances: (N, 2, 2) m^2.
    used: (N, C) bool, cue c entered the fusion. outvoted: (N, C) bool, cue c had an
    estimate but failed the gate. valid: (N,) bool, at least one cue was used.
    """

    positions: np.ndarray
    covariances: np.ndarray
    used: np.ndarray
    outvoted: np.ndarray
    valid: np.ndarray


def _information(cov: np.ndarray, use: np.ndarray) -> np.ndarray:
    """(N, C, 2, 2) inverse covariances, 0 for cues not in use."""
    return np.where(use[..., None, None], inverse_2x2(cov), 0.0)


def _combine(info: np.ndarray, means: np.ndarray):
    """Sum of information (N, 2, 2) and the information-weighted mean (N, 2) of cues (N, C, ...)."""
    total = info.sum(axis=1)
    vec = np.einsum("ncab,ncb->na", info, means)
    return total, vec


def fuse_cues(cues: list[CueEstimate], gate_probability: float) -> Fused:
    """Gate and fuse N pedestrians' cue estimates (all cues have the same N)."""
    n, c = len(cues[0]), len(cues)
    means = np.stack([q.positions for q in cues], axis=1)  # (N, C, 2)
    covs = np.stack([q.covariances for q in cues], axis=1)  # (N, C, 2, 2)
    has = np.stack([q.valid for q in cues], axis=1)  # (N, C)
    use = has.copy()
    threshold = chi2_quantile_2dof(gate_probability)
    trust = np.array([TRUST_ORDER.index(q.name) if q.name in TRUST_ORDER else len(TRUST_ORDER) for q in cues])
    for _ in range(c - 1):
        info = _information(covs, use)
        total, vec = _combine(info, means)
        rest_info = total[:, None] - info  # (N, C, 2, 2) the others' information
        others = use.sum(axis=1, keepdims=True) - use > 0
        testable = use & others
        rest_info = np.where(testable[..., None, None], rest_info, np.eye(2))
        rest_cov = inverse_2x2(rest_info)
        rest_mean = np.einsum("ncab,ncb->nca", rest_cov, vec[:, None] - np.einsum("ncab,ncb->nca", info, means))
        diff = means - rest_mean
        joint = np.where(testable[..., None, None], covs + rest_cov, np.eye(2))
        d2 = np.where(testable, np.einsum("nca,ncab,ncb->nc", diff, inverse_2x2(joint), diff), -np.inf)
        # the worst cue; among equal distances (always so between two cues) the less trusted one
        score = np.where(testable, d2 * (1.0 + 1e-6 * trust[None, :]), -np.inf)
        worst = np.argmax(score, axis=1)
        drop = d2[np.arange(n), worst] > threshold
        if not drop.any():
            break
        use[np.flatnonzero(drop), worst[drop]] = False
    info = _information(covs, use)
    total, vec = _combine(info, means)
    valid = use.any(axis=1)
    total = np.where(valid[:, None, None], total, np.eye(2))
    cov = inverse_2x2(total)
    pos = np.einsum("nab,nb->na", cov, vec)
    cov = 0.5 * (cov + np.transpose(cov, (0, 2, 1)))
    return Fused(np.where(valid[:, None], pos, 0.0), cov, use, has & ~use, valid)
