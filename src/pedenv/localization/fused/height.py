"""Height cue: keypoints whose height above the ground is a known share of body height.

An upright person of height ``H`` at horizontal range ``r`` puts keypoint ``k`` (height
``f_k H`` above its own ground, ``c`` below the camera) on a ray whose elevation has

    tan_k = c / r + (H / r) f_k        (one row per seen keypoint of the table below)

A weighted straight-line fit of ``tan_k`` over ``f_k`` gives the slope ``H / r`` without
assuming where the ground is (so rolling terrain does not bias it); the rows' noise is
the pixel noise plus the spread of the fraction (head tilt, pelvis bob). Of two seen
ankles only the lower (the stance foot) is used; a lone ankle may be lifted and counts less. The spread
of human heights (``person_height_std_m``, about 5 %; for a tracked person the same spread about
their learned height, :mod:`~pedenv.localization.fused.body_height`) scales the
range as a whole and repeats every frame for the same person, so it is the cue's per-person covariance; the
keypoint noise (each skeleton's own, :func:`~pedenv.localization.fused.cue.observed_angle_std`) and the
fractions' spread (gait, head tilt) are new every frame.
"""

import numpy as np

from pedenv.body import STANDING
from pedenv.config import FusedConfig
from pedenv.localization.fused.body_height import prior_std
from pedenv.localization.fused.cue import (
    LATERAL_STD_M,
    CueEstimate,
    FrameSkeletons,
    first_reason,
    horizontal_bearing,
    range_bearing_covariance,
)
from pedenv.skeleton import ANKLE_KEYPOINTS, NUM_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP

NAME = "height"

#: Spread of each keypoint's height fraction (head tilt, shoulders and pelvis riding on
#: the gait, a foot lifted in the swing phase), as a share of body height; NaN: the
#: keypoint has no fixed height (knees, arms) and the cue does not use it.
KEYPOINT_FRACTION_STD = np.full(NUM_KEYPOINTS, np.nan)
KEYPOINT_FRACTION_STD[[KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE, KP.LEFT_EAR, KP.RIGHT_EAR, KP.LEFT_SHOULDER,
                       KP.RIGHT_SHOULDER]] = 0.012
KEYPOINT_FRACTION_STD[[KP.LEFT_HIP, KP.RIGHT_HIP]] = 0.015
KEYPOINT_FRACTION_STD[[KP.LEFT_ANKLE, KP.RIGHT_ANKLE]] = 0.025
#: Height above the ground of an upright adult's keypoints, as a share of body height
#: (the body template, :data:`pedenv.body.STANDING`); NaN where the cue uses none.
KEYPOINT_HEIGHT_FRACTION = np.where(np.isfinite(KEYPOINT_FRACTION_STD), STANDING[:, 2], np.nan)
#: Spread of a lone ankle's fraction: with the other ankle unseen it may be the swing
#: foot, lifted up to ~0.15 (of two seen ankles only the lower, the stance foot, is used).
LONE_ANKLE_FRACTION_STD = 0.025
#: The ankles' share of body height (where the table's span starts).
ANKLE_FRACTION = float(KEYPOINT_HEIGHT_FRACTION[KP.LEFT_ANKLE])
#: Keypoints the height cue can use.
HEIGHT_KEYPOINTS = np.flatnonzero(np.isfinite(KEYPOINT_HEIGHT_FRACTION))
#: Columns of :data:`HEIGHT_KEYPOINTS` that are the ankles (left, right), and a mask of them.
ANKLE_COLUMNS = [int(np.flatnonzero(a == HEIGHT_KEYPOINTS)[0]) for a in ANKLE_KEYPOINTS]
IS_ANKLE = np.isin(HEIGHT_KEYPOINTS, ANKLE_KEYPOINTS)
#: The used keypoints must span at least this share of body height (e.g. head to hips).
MIN_FRACTION_SPAN = 0.25
#: Reweighting passes of the least squares (the row noise depends on the range).
PASSES = 2
#: A fitted range below this (metres) is no person in front of the camera.
MIN_RANGE_M = 0.3
#: A fitted range whose frame-to-frame standard deviation exceeds this share of itself is
#: no range: the keypoints' elevations do not resolve the slope (a skeleton collapsed to a
#: point or a line fits a slope of rounding noise, 1e16 m away with a 1e55 m^2 covariance
#: that broke the filter's arithmetic). Such a slope is not surely positive, so the cue
#: declines (``inconsistent``) rather than claim a range it cannot tell from infinity.
MAX_RELATIVE_RANGE_STD = 1.0
#: Relative determinant below which the straight-line fit is singular.
MIN_RELATIVE_DET = 1e-12
#: A track's last range scales this frame's variance only while this frame's range lies
#: within this many of the cue's standard deviations of it; farther, the track has taken
#: someone else (or a false detection) or come back after a long gap, and a variance scaled
#: at the old range would be far too small (a 15 px ghost 150 m away scaled at 20 m).
REFERENCE_RANGE_SIGMAS = 3.0


def solve_range(tangents: np.ndarray, fractions: np.ndarray, fraction_std: np.ndarray, used: np.ndarray,
                height_m: np.ndarray, angle_std: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fit ``tan_k = alpha + beta f_k`` for N people; the range is ``r = H / beta``.

    The elevations are the noisy side, so they are the dependent variable (fitting the
    ranges the other way round would shrink them towards the camera as noise grows).
    tangents, fractions, fraction_std: (N, K). used: (N, K) bool. height_m: (N,) metres.
    angle_std: noise of ``tan`` per keypoint (pixel noise / focal length), scalar or (N,).
    Returns ``(r (N,), var_pixel (N,), var_fraction (N,))``: horizontal range in metres
    and the parts of its variance from the pixel noise and from the fractions' spread
    (not yet the spread of heights); NaN where the rows do not determine it.
    """
    pixel = np.broadcast_to(np.asarray(angle_std, float), (len(tangents),))[:, None] ** 2
    beta = np.zeros(len(tangents))
    for _ in range(PASSES):  # the fraction's spread shows in tan scaled by the slope
        frac_var = (fraction_std * beta[:, None]) ** 2
        w = np.where(used, 1.0 / np.maximum(pixel + frac_var, 1e-18), 0.0)
        sw, sf, sff = w.sum(1), (w * fractions).sum(1), (w * fractions**2).sum(1)
        st, sft = (w * tangents).sum(1), (w * fractions * tangents).sum(1)
        det = sw * sff - sf * sf
        ok = det > MIN_RELATIVE_DET * np.maximum(sw * sff, 1e-300)
        safe = np.where(ok, det, 1.0)
        beta = np.where(ok, (sw * sft - sf * st) / safe, 0.0)
    # beta = sum_k g_k tan_k with g_k = w_k (sw f_k - sf) / det: each row's noise adds g_k^2 noise_k
    g2 = (w * (sw[:, None] * fractions - sf[:, None]) / safe[:, None]) ** 2
    var_pix, var_frac = (g2 * pixel).sum(1), (g2 * (fraction_std * beta[:, None]) ** 2).sum(1)
    positive = ok & (beta > 0)
    safe_beta = np.where(positive, beta, 1.0)
    r = np.where(positive, height_m / safe_beta, np.nan)
    to_range = r**2 / safe_beta**2
    return r, var_pix * to_range, var_frac * to_range


def height_cue(skeletons: FrameSkeletons, config: FusedConfig,
               height_mean: np.ndarray | None = None, height_std: np.ndarray | None = None,
               reference_range: np.ndarray | None = None) -> CueEstimate:
    """Ground point of N pedestrians from the known body-height shares of their keypoints.

    skeletons: the frame's rays (world), usable keypoints and stance ankles.
    height_mean, height_std: (N,) metres, each person's
    height as its keypoints' span reads it, and its spread (default: the population prior of
    ``config``, :func:`~pedenv.localization.fused.body_height.prior_std`; a track's own:
    :func:`~pedenv.localization.fused.body_height.track_heights`). reference_range: (N,)
    metres, the range at which to scale the variance (NaN or None: this frame's range).
    The variance grows with the range squared; scaled at this frame's noisy range, a
    too-near estimate would count more than a too-far one and a filter averaging them
    would drift near, so a tracked pedestrian's variance is scaled at its last range, as
    long as this frame's range agrees with it (:data:`REFERENCE_RANGE_SIGMAS`).
    Declines with ``no-keypoints`` (fewer than two usable levels), ``short-extent``
    (they span too little of the body) or ``inconsistent`` (no positive range fits, or
    the fit's range is not resolved: :data:`MAX_RELATIVE_RANGE_STD`).
    """
    n, idx = len(skeletons), HEIGHT_KEYPOINTS
    hm = np.full(n, config.person_height_mean_m) if height_mean is None else np.asarray(height_mean, float)
    hs = np.full(n, prior_std(config)) if height_std is None else np.asarray(height_std, float)
    used = skeletons.usable[:, idx]
    used[:, ANKLE_COLUMNS] = skeletons.stance
    frac = KEYPOINT_HEIGHT_FRACTION[idx]
    span = np.where(used, frac, -np.inf).max(1) - np.where(used, frac, np.inf).min(1)
    levels = used.sum(axis=1)
    enough = (levels >= 2) & (span >= MIN_FRACTION_SPAN)
    if not enough.any():
        return CueEstimate.declined(NAME, first_reason([(levels < 2, "no-keypoints"), (~enough, "short-extent")], n))
    frac_std = np.where(IS_ANKLE[None] & skeletons.lone[:, None], LONE_ANKLE_FRACTION_STD, KEYPOINT_FRACTION_STD[idx])
    used &= enough[:, None]
    # the pose source's span is keypoint_span_scale of the table's: shrink the fractions about
    # the ankle so that a skeleton of that span reads the right body height
    scaled = ANKLE_FRACTION + config.keypoint_span_scale * (frac - ANKLE_FRACTION)
    r, var_pix, var_frac = solve_range(skeletons.tangents[:, idx], np.broadcast_to(scaled, used.shape), frac_std,
                                       used, hm, skeletons.noise)
    with np.errstate(over="ignore", invalid="ignore"):  # NaN and inf compare False
        resolved = var_pix + var_frac <= MAX_RELATIVE_RANGE_STD**2 * r**2
    good = enough & np.isfinite(r) & (r > MIN_RANGE_M) & np.isfinite(var_pix + var_frac) & resolved
    reasons = first_reason([(levels < 2, "no-keypoints"), (~enough, "short-extent"), (~good, "inconsistent")], n)
    r = np.where(good, r, 1.0)
    r2 = r**2
    frame_rel = np.where(good, (var_pix + var_frac) / r2, 1.0)
    bias_rel = (hs / hm) ** 2  # height spread and posture, per person
    scale = r
    if reference_range is not None:
        ref = np.asarray(reference_range, float)
        with np.errstate(invalid="ignore"):  # NaN: no reference
            agrees = (r - ref) ** 2 <= REFERENCE_RANGE_SIGMAS**2 * (frame_rel + bias_rel) * np.fmax(r, ref) ** 2
        scale = np.where(agrees, ref, r)
    mean_ray = np.where(used[..., None], skeletons.rays[:, idx], 0.0).sum(axis=1)
    bearing = horizontal_bearing(mean_ray)
    xy = skeletons.origin[:2] + r[:, None] * bearing
    s2 = scale**2
    across = (scale * skeletons.noise) ** 2  # the body's own sideways spread is the person's
    return CueEstimate(NAME, xy, range_bearing_covariance(bearing, frame_rel * s2, across),
                       range_bearing_covariance(bearing, bias_rel * s2, LATERAL_STD_M**2), good, reasons)
