"""Each track's body height, learned over its life from the cues that do not assume it.

The height cue places a person at ``H / beta`` (``beta`` the slope its keypoints fit,
:mod:`~pedenv.localization.fused.height`), so its error is the person's unknown height, a
constant of the track. Another cue that finds the range ``r`` without a body height (the
feet on the road, the triangulation) measures it: ``H_k = H_used r_k / r_height``, with the
relative variance of both ranges. Part of such a measurement's error is new every frame (pixel
noise, the gait, the car's pitching) and averages out over a track; part repeats for the same
person (the road under them off the vehicle's plane, a raised pavement; a walker's drift in
the triangulation) and does not. So each track keeps, per cue, the sums of the measurements
weighted by their frame-to-frame information ``w_k``: ``sum w``, ``sum w H`` and ``sum w s``
(``s`` the per-person spread in metres of height, summed as fully correlated). The cue's height
is then ``sum w H / sum w`` with variance ``1 / sum w + (sum w s / sum w)^2``; each cue's
height is fused with the prior ``N(person_height_mean_m, prior spread)``
(:func:`prior_std`) into the track's height, which the height cue then uses. Its spread, which
goes into the height cue's per-person covariance, stays the prior's: on the real KITTI tracking
drives (skeletons rendered from the labels) the learned heights move little (the tracks' learned
heights spread 0.005-0.025 m about their mean within a drive, where the labelled heights spread 0.15 m
per track), so a spread narrowed by the fusion claimed what was not learned; there, the parked drive
0016 had 1/2-sigma coverage 13.2/75.6 % with the prior's spread and 11.5/74.5 % with the narrowed one.

Under a static camera no heights are learned: its calibrated ground cue is trusted first, and the
detector's per-person keypoint offsets, which its exact ground does not cover, would then be
learned as heights (the static synthetic plaza, detector model: 0.62 -> 0.67 %).

The height is that of the keypoints' span (what the height cue reads), so the pose source's
posture spread (``keypoint_span_std``) is part of the prior and is learned with the rest.
"""

from __future__ import annotations

import numpy as np

from pedenv.config import FusedConfig
from pedenv.localization.fused.cue import CueEstimate

#: A height measurement is kept only between these heights (metres): a child of 0.8 m to a
#: tall adult; outside, one of the two ranges is wrong (a cue that hit the wrong person).
HEIGHT_RANGE_M = (0.8, 2.3)
#: A measurement farther than this many of its standard deviations (its own spread and the
#: track's) from the track's height is left out: the track took someone else, or the cue
#: was outvoted for a reason of its own (a runaway triangulation).
GATE_SIGMAS = 4.0


def prior_std(config: FusedConfig) -> float:
    """The spread (metres) of a person's height as the height cue reads it before any
    measurement: body heights (``person_height_std_m``) and the keypoints' span against
    them (``keypoint_span_std`` of the mean)."""
    return float(np.hypot(config.person_height_std_m, config.keypoint_span_std * config.person_height_mean_m))


def along_variance(covariances: np.ndarray, bearing: np.ndarray) -> np.ndarray:
    """(N,) m^2, the variance of (N, 2, 2) ``covariances`` along the unit ``bearing`` (N, 2)."""
    return np.einsum("ni,nij,nj->n", bearing, covariances, bearing)


def height_measurements(height: CueEstimate, other: CueEstimate, origin: np.ndarray,
                        used_heights: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What ``other`` (a cue that needs no body height) says of N people's heights.

    height: the height cue, placed with ``used_heights`` (N,) metres. origin: (3,) camera
    centre, world, metres. Returns ``(heights (N,) metres, frame variance (N,) m^2, per-person
    spread (N,) metres, valid (N,) bool)``; the variances are the relative ones of both ranges
    along the height cue's ray times the height squared.
    """
    offset_h, offset_o = height.positions - origin[:2], other.positions - origin[:2]
    r_h = np.sqrt((offset_h**2).sum(1))
    bearing = offset_h / np.maximum(r_h, 1e-9)[:, None]
    r_o = (offset_o * bearing).sum(1)  # the other cue's range along the same ray
    valid = height.valid & other.valid & (r_h > 0) & (r_o > 0)
    r_h, r_o = np.where(valid, r_h, 1.0), np.where(valid, r_o, 1.0)
    h = used_heights * r_o / r_h
    frame_rel = (along_variance(height.covariances, bearing) / r_h**2
                 + along_variance(other.covariances, bearing) / r_o**2)
    spread = h * np.sqrt(along_variance(other.bias_covariances, bearing)) / r_o
    with np.errstate(invalid="ignore"):
        valid &= np.isfinite(h + frame_rel + spread) & (h >= HEIGHT_RANGE_M[0]) & (h <= HEIGHT_RANGE_M[1])
    return h, frame_rel * h**2, spread, valid


def cue_height(sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N,) metres and (N,) m^2: one cue's height of N tracks and its variance from the
    sums (N, 3) ``(sum w, sum w H, sum w s)``; variance inf where the track has none."""
    w = sums[:, 0]
    some = w > 0
    safe = np.where(some, w, 1.0)
    return np.where(some, sums[:, 1] / safe, 0.0), np.where(some, 1.0 / safe + (sums[:, 2] / safe) ** 2, np.inf)


def track_heights(sums: np.ndarray, config: FusedConfig) -> tuple[np.ndarray, np.ndarray]:
    """(N,) metres, each track's height and (N,) metres its spread: the prior fused with each
    cue's height, the spread no narrower than the prior's (module notes). sums: (N, C, 3) per
    cue ``(sum w, sum w H, sum w s)``."""
    prior_var = prior_std(config) ** 2
    information = np.full(len(sums), 1.0 / prior_var)
    weighted = information * config.person_height_mean_m
    for c in range(sums.shape[1]):
        h, var = cue_height(sums[:, c])
        information = information + 1.0 / var
        weighted = weighted + h / var
    return weighted / information, np.sqrt(1.0 / np.minimum(information, 1.0 / prior_var))


def add_measurements(sums: np.ndarray, track_mean: np.ndarray, track_std: np.ndarray,
                     measured: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> np.ndarray:
    """``sums`` (N, 3) of one cue with this frame's ``measured`` heights added
    (:func:`height_measurements`), each within :data:`GATE_SIGMAS` of the track's height
    ``track_mean`` (N,) metres with spread ``track_std`` (N,) metres."""
    h, frame_var, spread, valid = measured
    with np.errstate(invalid="ignore"):
        near = (h - track_mean) ** 2 <= GATE_SIGMAS**2 * (track_std**2 + frame_var + spread**2)
    take = valid & near
    w = np.where(take, 1.0 / np.where(take, frame_var, 1.0), 0.0)
    return sums + np.column_stack([w, w * np.where(take, h, 0.0), w * np.where(take, spread, 0.0)])
