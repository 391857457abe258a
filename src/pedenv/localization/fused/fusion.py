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

The 2x2 algebra is written out on the components ``(xx, xy, yy)`` of (N, C) arrays:
on a few pedestrians a frame, stacking small matrices costs more than the arithmetic.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.geometry import inverse_2x2_entries
from pedenv.localization.fused.cue import REASON_CODE, REASONS, CueEstimate

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


def inverse_sym(a, b, c):
    """Inverse ``(a', b', c')`` of symmetric 2x2 matrices ``[[a, b], [b, c]]`` (arrays)."""
    ia, ib, _, ic = inverse_2x2_entries(a, b, b, c)
    return ia, ib, ic


def sandwich(m, f):
    """Components of ``M F M`` for symmetric 2x2 ``M = (a, b, c)`` and ``F = (a, b, c)``."""
    (a, b, c), (fa, fb, fc) = m, f
    p, q, r, s = a * fa + b * fb, a * fb + b * fc, b * fa + c * fb, b * fb + c * fc  # M F
    return p * a + q * b, p * b + q * c, r * b + s * c


def _components(cues: list[CueEstimate], field: str):
    stacked = np.stack([getattr(q, field) for q in cues], axis=1)  # (N, C, 2, 2)
    return stacked[..., 0, 0], 0.5 * (stacked[..., 0, 1] + stacked[..., 1, 0]), stacked[..., 1, 1]


def fuse_cues(cues: list[CueEstimate], gate_probability: float, origin: np.ndarray | None = None,
              trust_order: tuple[str, ...] = TRUST_ORDER) -> Fused:
    """Gate and fuse N pedestrians' cue estimates (all cues have the same N).

    origin: (2,) camera centre, world x-y, metres; given, the fused covariance across each
    pedestrian's viewing ray is floored at the sharpest used cue's (see the module notes).
    trust_order: which cue stays when two disagree (:data:`STATIC_TRUST_ORDER`: static cameras).
    """
    n, c = len(cues[0]), len(cues)
    means = np.stack([q.positions for q in cues], axis=1)  # (N, C, 2)
    fa, fb, fc = _components(cues, "covariances")
    ba, bb, bc = _components(cues, "bias_covariances")
    sa, sb, sc = fa + ba, fb + bb, fc + bc
    has = np.stack([q.valid for q in cues], axis=1)  # (N, C)
    with np.errstate(invalid="ignore", over="ignore"):
        finite = (np.isfinite(means).all(axis=-1) & np.isfinite(sa + sb + sc + fa + fb + fc)
                  & (sa > 0) & (sa * sc - sb * sb > 0))
    degenerate = has & ~finite
    use = has & finite
    mx, my = np.where(use, means[..., 0], 0.0), np.where(use, means[..., 1], 0.0)
    sa, sb, sc = np.where(use, sa, 1.0), np.where(use, sb, 0.0), np.where(use, sc, 1.0)
    ia, ib, ic = inverse_sym(sa, sb, sc)
    threshold = chi2_quantile_2dof(gate_probability)
    rank = np.array([trust_order.index(q.name) if q.name in trust_order else len(trust_order) for q in cues])
    rows = np.arange(n)
    for _ in range(c - 1):
        count = use.sum(axis=1, keepdims=True)
        testable = use & (count > 1)
        if not testable.any():
            break
        ua, ub, uc = np.where(use, ia, 0.0), np.where(use, ib, 0.0), np.where(use, ic, 0.0)
        vx, vy = ua * mx + ub * my, ub * mx + uc * my  # each cue's information times its mean
        # the others' information and information-weighted mean (identity where none)
        ra = np.where(testable, ua.sum(1, keepdims=True) - ua, 1.0)
        rb = np.where(testable, ub.sum(1, keepdims=True) - ub, 0.0)
        rc = np.where(testable, uc.sum(1, keepdims=True) - uc, 1.0)
        qa, qb, qc = inverse_sym(ra, rb, rc)
        rx, ry = vx.sum(1, keepdims=True) - vx, vy.sum(1, keepdims=True) - vy
        dx, dy = mx - (qa * rx + qb * ry), my - (qb * rx + qc * ry)
        ja, jb, jc = inverse_sym(sa + qa, sb + qb, sc + qc)
        d2 = ja * dx * dx + 2.0 * jb * dx * dy + jc * dy * dy
        score = np.where(testable, d2 * (1.0 + TIE_BREAK * rank), -np.inf)
        worst = np.argmax(score, axis=1)
        drop = score[rows, worst] > threshold
        if not drop.any():
            break
        use[rows[drop], worst[drop]] = False
    ua, ub, uc = np.where(use, ia, 0.0), np.where(use, ib, 0.0), np.where(use, ic, 0.0)
    valid = use.any(axis=1)
    ta, tb, tc = ua.sum(1), ub.sum(1), uc.sum(1)
    ta, tc = np.where(valid, ta, 1.0), np.where(valid, tc, 1.0)
    pa, pb, pc = inverse_sym(ta, tb, tc)
    vx, vy = (ua * mx + ub * my).sum(1), (ub * mx + uc * my).sum(1)
    pos = np.column_stack([pa * vx + pb * vy, pb * vx + pc * vy])
    ga, gb, gc = sandwich((ua, ub, uc), (fa, fb, fc))  # S_c^-1 F_c S_c^-1, 0 for unused cues
    fa_, fb_, fc_ = sandwich((pa, pb, pc), (ga.sum(1), gb.sum(1), gc.sum(1)))
    frame = np.empty((n, 2, 2))
    frame[:, 0, 0], frame[:, 1, 1], frame[:, 0, 1], frame[:, 1, 0] = fa_, fc_, fb_, fb_
    bias = np.empty((n, 2, 2))
    bias[:, 0, 0], bias[:, 1, 1], bias[:, 0, 1], bias[:, 1, 0] = pa - fa_, pc - fc_, pb - fb_, pb - fb_
    if origin is not None:
        bearing_floor(pos - np.asarray(origin, float)[:2], use, (fa, fb, fc), (ba, bb, bc), frame, bias)
    return Fused(pos, frame, bias, use, has & finite & ~use, degenerate, valid)


def bearing_floor(offsets: np.ndarray, use: np.ndarray, cue_frame, cue_bias, frame: np.ndarray,
                  bias: np.ndarray) -> None:
    """Raise the fused variances across the ray to the sharpest used cue's, in place.

    offsets: (N, 2) fused position minus camera centre, metres. use: (N, C) bool.
    cue_frame, cue_bias: components ``(xx, xy, yy)`` (N, C) of the cues' frame-to-frame and
    per-person covariances. frame, bias: (N, 2, 2) the fused ones, m^2, updated.
    """
    norm = np.sqrt((offsets**2).sum(1))
    ux = np.where(norm > 0, -offsets[:, 1] / np.maximum(norm, 1e-12), 0.0)[:, None]  # across the ray
    uy = np.where(norm > 0, offsets[:, 0] / np.maximum(norm, 1e-12), 0.0)[:, None]
    across = lambda c: c[0] * ux * ux + 2.0 * c[1] * ux * uy + c[2] * uy * uy  # noqa: E731
    f_c, b_c = across(cue_frame), across(cue_bias)  # (N, C)
    sharpest = np.argmin(np.where(use, f_c + b_c, np.inf), axis=1)
    rows = np.arange(len(offsets))
    u = np.column_stack([ux[:, 0], uy[:, 0]])
    outer = u[:, :, None] * u[:, None, :]
    for fused, per_cue in ((frame, f_c), (bias, b_c)):
        now = np.einsum("ni,nij,nj->n", u, fused, u)
        lift = np.where(use.any(1), np.maximum(per_cue[rows, sharpest] - now, 0.0), 0.0)
        fused += lift[:, None, None] * outer


def describe_sources(cues: list[CueEstimate], fused: Fused, cache: dict, prefix: np.ndarray) -> np.ndarray:
    """(N,) str: used cues joined by ``+``, then ``;cue:reason`` for each cue left out
    (``outvoted`` by the gate, ``degenerate`` numbers, else the cue's own reason); the
    name ``box`` in front where ``prefix`` (N,) bool (no cue placed the pedestrian).

    cache: a dict kept between frames; the few distinct combinations are spelled once.
    """
    degenerate = REASON_CODE["degenerate"]
    outvoted = degenerate + 1
    key = prefix.astype(np.int64)
    base = outvoted + 2
    for c, cue in enumerate(cues):
        code = np.where(fused.used[:, c], outvoted + 1,
                        np.where(fused.outvoted[:, c], outvoted,
                                 np.where(fused.degenerate[:, c], degenerate, cue.reasons)))
        key = key * base + code
    names = tuple(q.name for q in cues)
    out = []
    for k in key.tolist():
        text = cache.get((names, k))
        if text is None:
            text = cache[(names, k)] = _spell(names, k, base, outvoted)
        out.append(text)
    return np.array(out)


def _spell(names: tuple[str, ...], key: int, base: int, outvoted: int) -> str:
    codes = []
    for _ in names:
        key, code = divmod(key, base)
        codes.append(code)
    codes.reverse()
    box = "box" if key else ""
    head = "+".join(name for name, code in zip(names, codes) if code == outvoted + 1)
    tail = "".join(f";{name}:{'outvoted' if code == outvoted else REASONS[code]}"
                   for name, code in zip(names, codes) if 0 < code <= outvoted)
    return box + head + tail
