"""Information-weighted fusion of the cues, with a chi-square gate against a bad cue.

For cue estimates ``(mu_c, S_c)`` (``S_c`` the whole error: frame-to-frame part ``F_c``
plus the per-person part ``B_c``) the fused estimate is ``S = (sum S_c^-1)^-1``,
``mu = S sum S_c^-1 mu_c``. Before that, each cue is compared with the fusion of the
others: ``d^2 = (mu_c - mu_rest)^T (S_c + S_rest)^-1 (mu_c - mu_rest)``. While the worst
``d^2`` exceeds the chi-square quantile (2 dof) that cue is dropped, so a bad cue is
outvoted, not averaged in. Between two cues only, the one later in the trust order is
dropped (the height cue is trusted most: terrain and a walking person bias the others;
under a static camera the ground is the calibrated plane, so its ground cue goes first).

The fused error is ``S sum S_c^-1 e_c``; with the cues' errors independent its
frame-to-frame part is ``F = S (sum S_c^-1 F_c S_c^-1) S`` and its per-person part
``B = S - F``.

Across the viewing ray the cues are not independent: they read the bearing off the same
person's keypoints and the same body (its lean, where the feet stand), so fusing them
cannot make the position sharper sideways than the sharpest cue alone. Given the camera
position, the fused covariance across the ray is floored at that cue's (the bearing floor),
frame-to-frame and per-person parts each; without it two cues halve a sideways variance
whose error they share (on the real KITTI frames: sideways sigma 3 cm, errors 2-9 cm).

The 2x2 algebra is written on the components ``(xx, xy, yy)`` of (N, C) arrays
(:class:`~pedenv.localization.fused.cue.Sym2`): on a few pedestrians a frame, stacking
small matrices costs more than the arithmetic. :class:`StackedCues` holds each cue's
mean and covariance side by side; :func:`outvote` is the gate, :func:`combine` the fusion.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.localization.fused.cue import IDENTITY, ZERO, CueEstimate, Sym2

#: Which cue to keep when only two disagree: earlier in this tuple wins.
TRUST_ORDER = ("height", "triangulation", "ground")
#: The same for a static camera (``Camera.mount``): its ground plane and height are exact,
#: while the height cue leans on a body-height prior and upright-body proportions.
STATIC_TRUST_ORDER = ("ground", "height", "triangulation")
#: Between equal gate distances the less trusted cue goes: distances are scaled by
#: ``1 + TIE_BREAK * rank`` (small enough never to change a real ordering).
TIE_BREAK = 1e-6


def chi2_quantile_2dof(probability: float) -> float:
    """The chi-square quantile with 2 degrees of freedom: ``-2 ln(1 - p)``."""
    return float(-2.0 * np.log1p(-probability))


@dataclass(frozen=True)
class Fused:
    """The fused estimate of N pedestrians.

    positions: (N, 2) world x-y, metres. covariances: (N, 2, 2) m^2, frame-to-frame part.
    bias_covariances: (N, 2, 2) m^2, the part that repeats for the same person.
    used: (N, C) bool, cue c entered the fusion. outvoted: (N, C) bool, cue c had an
    estimate but failed the gate. degenerate: (N, C) bool, cue c had an estimate whose
    numbers were not finite (treated as declined). valid: (N,) bool, a cue was used.
    """

    positions: np.ndarray
    covariances: np.ndarray
    bias_covariances: np.ndarray
    used: np.ndarray
    outvoted: np.ndarray
    degenerate: np.ndarray
    valid: np.ndarray


@dataclass(frozen=True)
class StackedCues:
    """The C cues' estimates of N pedestrians side by side: each cue's mean and covariance together.

    x, y: (N, C) mean, world x-y, metres. frame, bias: (N, C) :class:`Sym2`, m^2, the
    frame-to-frame and per-person parts of the covariance. has: (N, C) bool, cue c has an
    estimate. rank: (C,) int, each cue's place in the trust order (later: dropped first).
    """

    x: np.ndarray
    y: np.ndarray
    frame: Sym2
    bias: Sym2
    has: np.ndarray
    rank: np.ndarray

    @classmethod
    def of(cls, cues: list[CueEstimate], trust_order: tuple[str, ...]) -> StackedCues:
        means = np.stack([q.positions for q in cues], axis=1)  # (N, C, 2)
        rank = [trust_order.index(q.name) if q.name in trust_order else len(trust_order) for q in cues]
        return cls(means[..., 0], means[..., 1], Sym2.of(np.stack([q.covariances for q in cues], axis=1)),
                   Sym2.of(np.stack([q.bias_covariances for q in cues], axis=1)),
                   np.stack([q.valid for q in cues], axis=1), np.array(rank))

    @property
    def total(self) -> Sym2:
        """(N, C) the whole covariance, frame-to-frame plus per-person part, m^2."""
        return self.frame + self.bias

    def finite(self) -> np.ndarray:
        """(N, C) bool: finite mean and covariances, the whole covariance positive definite."""
        s, f = self.total, self.frame
        with np.errstate(invalid="ignore", over="ignore"):
            return (np.isfinite(self.x) & np.isfinite(self.y) & np.isfinite(s.xx + s.xy + s.yy + f.xx + f.xy + f.yy)
                    & (s.xx > 0) & (s.xx * s.yy - s.xy * s.xy > 0))


def fuse_cues(cues: list[CueEstimate], gate_probability: float, origin: np.ndarray | None = None,
              trust_order: tuple[str, ...] = TRUST_ORDER) -> Fused:
    """Gate and fuse N pedestrians' cue estimates (all cues have the same N).

    origin: (2,) camera centre, world x-y, metres; given, the fused covariance across each
    pedestrian's viewing ray is floored at the sharpest used cue's (see the module notes).
    trust_order: which cue stays when two disagree (:data:`STATIC_TRUST_ORDER`: static cameras).
    """
    stack = StackedCues.of(cues, trust_order)
    finite = stack.finite()
    use = stack.has & finite
    x, y = np.where(use, stack.x, 0.0), np.where(use, stack.y, 0.0)
    total = stack.total.where(use, IDENTITY)
    information = total.inverse()
    outvote(use, x, y, total, information, chi2_quantile_2dof(gate_probability), stack.rank)
    positions, frame, bias = combine(use, x, y, information.where(use, ZERO), stack.frame)
    if origin is not None:
        bearing_floor(positions - np.asarray(origin, float)[:2], use, stack.frame, stack.bias, frame, bias)
    return Fused(positions, frame, bias, use, stack.has & finite & ~use, stack.has & ~finite, use.any(axis=1))


def outvote(use: np.ndarray, x: np.ndarray, y: np.ndarray, total: Sym2, information: Sym2, threshold: float,
            rank: np.ndarray) -> None:
    """Drop each pedestrian's worst cue while its gate distance exceeds ``threshold``, in place.

    use: (N, C) bool, updated. x, y: (N, C) the cues' means, metres (0 where unused).
    total, information: (N, C) each cue's whole covariance (m^2) and its inverse (identity
    where unused). rank: (C,) trust ranks, breaking ties between equal distances.
    """
    rows = np.arange(len(use))
    for _ in range(use.shape[1] - 1):
        testable = use & (use.sum(axis=1, keepdims=True) > 1)
        if not testable.any():
            break
        d2 = gate_distances(x, y, total, information.where(use, ZERO), testable)
        score = np.where(testable, d2 * (1.0 + TIE_BREAK * rank), -np.inf)
        worst = np.argmax(score, axis=1)
        drop = score[rows, worst] > threshold
        if not drop.any():
            break
        use[rows[drop], worst[drop]] = False


def gate_distances(x: np.ndarray, y: np.ndarray, total: Sym2, information: Sym2, testable: np.ndarray) -> np.ndarray:
    """(N, C) ``d^2`` of each cue against the fusion of the others (module notes).

    information: (N, C) each used cue's, zero for the others. testable: (N, C) bool, the
    cue and another are used (elsewhere the result is meaningless).
    """
    wx, wy = information.times(x, y)  # each cue's information times its mean
    # the fusion of the others: its covariance (identity where there is none) and its mean
    others = (information.sum(keepdims=True) - information).where(testable, IDENTITY).inverse()
    others_x, others_y = others.times(wx.sum(1, keepdims=True) - wx, wy.sum(1, keepdims=True) - wy)
    return (total + others).inverse().quadratic(x - others_x, y - others_y)


def combine(use: np.ndarray, x: np.ndarray, y: np.ndarray, information: Sym2,
            cue_frame: Sym2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The information-weighted mean of the used cues and its covariance's two parts.

    use: (N, C) bool. x, y: (N, C) means, metres. information: (N, C) the used cues', zero
    for the others. cue_frame: (N, C) the cues' frame-to-frame covariances, m^2. Returns
    ``(positions (N, 2) metres, frame (N, 2, 2) m^2, bias (N, 2, 2) m^2)`` (module notes).
    """
    valid = use.any(axis=1)
    fused = information.sum().where(valid, IDENTITY).inverse()
    wx, wy = information.times(x, y)  # each cue's information times its mean
    positions = np.column_stack(fused.times(wx.sum(1), wy.sum(1)))
    frame = fused.sandwich(information.sandwich(cue_frame).sum())  # S (sum S_c^-1 F_c S_c^-1) S
    return positions, frame.matrices(), (fused - frame).matrices()


def bearing_floor(offsets: np.ndarray, use: np.ndarray, cue_frame: Sym2, cue_bias: Sym2, frame: np.ndarray,
                  bias: np.ndarray) -> None:
    """Raise the fused variances across the ray to the sharpest used cue's, in place.

    offsets: (N, 2) fused position minus camera centre, metres. use: (N, C) bool.
    cue_frame, cue_bias: (N, C) the cues' frame-to-frame and per-person covariances, m^2.
    frame, bias: (N, 2, 2) the fused ones, m^2, updated.
    """
    norm = np.sqrt((offsets**2).sum(1))
    ux = np.where(norm > 0, -offsets[:, 1] / np.maximum(norm, 1e-12), 0.0)[:, None]  # across the ray
    uy = np.where(norm > 0, offsets[:, 0] / np.maximum(norm, 1e-12), 0.0)[:, None]
    f_c, b_c = cue_frame.quadratic(ux, uy), cue_bias.quadratic(ux, uy)  # (N, C)
    sharpest = np.argmin(np.where(use, f_c + b_c, np.inf), axis=1)
    rows = np.arange(len(offsets))
    u = np.column_stack([ux[:, 0], uy[:, 0]])
    outer = u[:, :, None] * u[:, None, :]
    for fused, per_cue in ((frame, f_c), (bias, b_c)):
        now = np.einsum("ni,nij,nj->n", u, fused, u)
        lift = np.where(use.any(1), np.maximum(per_cue[rows, sharpest] - now, 0.0), 0.0)
        fused += lift[:, None, None] * outer
