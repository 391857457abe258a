"""The robust least-squares fit of a static camera to people's foot and head points.

Each person's foot point is cut with the ground (raised to the ankle keypoint's height), the
head keypoint is placed a mean person's span above it and projected back; the misfit to the
seen head point, in units of its expected spread (pixel noise and the spread of body heights,
:data:`PERSON_HEIGHT_STD_M`), is minimised over (f, H, tilt, roll) with a soft-L1 loss.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.sparse import lil_matrix

from pedenv.body import ANKLE, CROWD_MEAN_STD_M
from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.geometry import camera_rotation, ground_points, intrinsics, project
from pedenv.calibration.initial import closed_form
from pedenv.calibration.observations import Observations
from pedenv.calibration.refusals import check_result, check_spread

#: Prior of adult body height, metres (the fused method's ``person_height_mean_m`` and
#: ``person_height_std_m``: 1.72 m, 0.09 m; the paper's refinement assumes 1.7 m).
PERSON_HEIGHT_MEAN_M, PERSON_HEIGHT_STD_M = 1.72, 0.09
#: The fit's own 1-sigma (the clustered covariance) times this is its stated one: over 60
#: ``static-plaza`` scenes (seeds 0-59, detector model, ``benchmarks/self_calibration.py --only
#: seeds``) the errors of focal length, tilt and roll were 1.66, 1.26 and 1.46 times it (RMS of the
#: normalised errors; a +0.9 % focal bias the fit does not model), 1.11, 0.84 and 0.97 times it widened.
FIT_STD_SCALE = 1.5
#: A keypoint's pixel noise (the fused method's ``keypoint_pixel_std`` prior).
KEYPOINT_PIXEL_STD = 3.0
#: A head's sideways spread about the feet's vertical, share of the span (gait, lean, the
#: feet's midpoint against the body's axis).
SIDEWAYS_SHARE = 0.05
#: Spread of one person's ankle-to-head span from image to image, share of it: the synthetic
#: walker's gait moves the ankles' midpoint by 0.021 and the eyes by 0.010 of body height
#: (1-sigma) over a span of 0.857 of it. A person's height itself is a parameter of the fit
#: (one per track, prior :data:`PERSON_HEIGHT_STD_M`).
WITHIN_PERSON_SPAN_STD = 0.03
#: Ridge added to the unit-scaled information matrix before inverting it: a direction the data
#: fix less than this (relative) gets a variance about 1e12 times its parameter's scale.
UNFIXED_RIDGE = 1e-12
#: Misfit (in sigmas) above which a person-image is dropped before the final fit.
OUTLIER_SIGMA = 3.0
#: Bounds of the fitted forward offset of the head keypoint from the feet's vertical, along a
#: walker's direction of travel, metres (:func:`estimate_camera` ``walking``). A walker leans
#: forward and its ankles' midpoint trails the body's axis: the synthetic walker's ears sit 0.12 m
#: ahead of its ankles on average (its eyes 0.20 m); the bounds leave room for a network's own
#: placement.
FORWARD_BOUNDS_M = (-0.3, 0.3)
#: Least ground distance (metres) a track's feet cover between the images around one image for
#: its direction of travel to count: a standing person's facing is unknown (its head is placed
#: over its feet), and a walker (1-1.6 m/s) covers it in 0.2-0.3 s.
MIN_TRAVEL_M = 0.3
#: The direction of travel at an image spans this many of the track's images before and after
#: it (a path's turn is followed; 10 images are 0.3 s of a 30 Hz video, 1 s at 10 Hz).
TRAVEL_WINDOW = 5


#: How a walker's keypoints sit against an upright person's, shares of body height, averaged over
#: the stride: the ankles' midpoint rises (the swing foot is off the ground) and the head sinks
#: (the pelvis rides lower on a bent stance leg). Measured on the synthetic walker's exact 3D
#: skeletons (``pedenv.synthetic.walker`` at 1.0-1.6 m/s; ``static-plaza`` seed 0, 60 s, 13 500
#: walking person-images): ankles +0.025, ears -0.012, the ankle-to-ear span 0.958 of standing.
WALKING_ANKLE_RISE, WALKING_HEAD_DROP = 0.025, 0.012


@dataclass(frozen=True)
class BodyModel:
    """Where a pose source puts an upright person's keypoints.

    span_scale: the source's ankle-to-head span as a share of the anatomical table's
    (:mod:`pedenv.body`; the fused method's ``keypoint_span_scale``). ankle_offset_m: the
    ankle keypoint above the anatomical ankle, metres (``ankle_keypoint_offset_m``).
    walking_ankle_rise_m, walking_head_drop_m: how much higher a walker's ankle keypoints and
    lower its head keypoint sit than a standing person's, metres, on average over the stride
    (:data:`WALKING_ANKLE_RISE`, :data:`WALKING_HEAD_DROP`; used by the ``walking`` fit, whose
    tracks' travel tells walkers from standing people).
    """

    span_scale: float = 1.0
    ankle_offset_m: float = 0.0
    height_mean_m: float = PERSON_HEIGHT_MEAN_M
    height_std_m: float = PERSON_HEIGHT_STD_M
    walking_ankle_rise_m: float = WALKING_ANKLE_RISE * PERSON_HEIGHT_MEAN_M
    walking_head_drop_m: float = WALKING_HEAD_DROP * PERSON_HEIGHT_MEAN_M

    def ankle_m(self) -> float:
        return ANKLE * self.height_mean_m + self.ankle_offset_m

    def head_m(self, share: np.ndarray) -> np.ndarray:
        return (ANKLE + self.span_scale * (share - ANKLE)) * self.height_mean_m + self.ankle_offset_m


#: Where a real pose network (YOLO11n-pose) puts the keypoints: its ankle-to-eye span is 0.823 of
#: the true height on KITTI, 0.928 of the anatomical table's, and its ankle keypoint 0.039 m above
#: the anatomical ankle (the fused method's measured figures, ``pedenv.config_position``). Those
#: were measured on KITTI's pedestrians, walkers and standing people together, so no walker's
#: rise or drop is added on top of them.
NETWORK_BODY = BodyModel(span_scale=0.928, ankle_offset_m=0.039, walking_ankle_rise_m=0.0, walking_head_drop_m=0.0)


def _camera_count(focal: float | None, walking: bool = False) -> int:
    """Camera parameters in ``x``: H, tilt, roll[, f][, the head's forward offset]."""
    return (3 if focal is not None else 4) + int(walking)


def travel_directions(ground: np.ndarray, obs: Observations) -> np.ndarray:
    """(N, 2) unit ground direction of travel of each person-image: from its track's ground point
    :data:`TRAVEL_WINDOW` images before to the one as many after (clamped at the track's ends);
    zero where the track is unknown or moved less than :data:`MIN_TRAVEL_M` in between."""
    slots = _slots(obs)
    order = np.lexsort((obs.frames, slots))
    s = slots[order]
    start = np.searchsorted(s, s, side="left")
    stop = np.searchsorted(s, s, side="right") - 1
    at = np.arange(len(s))
    before = order[np.maximum(at - TRAVEL_WINDOW, start)]
    after = order[np.minimum(at + TRAVEL_WINDOW, stop)]
    step = np.zeros((len(obs), 2))
    step[order] = ground[after, :2] - ground[before, :2]
    length = np.linalg.norm(step, axis=1)
    moving = (slots >= 0) & np.isfinite(length) & (length >= MIN_TRAVEL_M)
    return np.where(moving[:, None], step / np.where(moving, length, 1.0)[:, None], 0.0)


def _predicted(x: np.ndarray, obs: Observations, body: BodyModel, centre: tuple[float, float],
               focal: float | None, travel: np.ndarray | None = None) -> np.ndarray:
    """(N, 2) pixels: each head keypoint its person's span above the ground under the feet (and,
    given ``travel`` ((N, 2) unit ground directions, zero for a standing person), ``x``'s forward
    offset along it, a walker's feet raised and head lowered by the body's walking figures), for
    ``x`` = (H, tilt, roll[, f][, forward m], one height scale per track): the person's height
    over the mean."""
    walking = travel is not None
    n_cam = _camera_count(focal, walking)
    f = focal if focal is not None else x[3]
    k, r = intrinsics(f, centre), camera_rotation(x[1], x[2])
    ground = ground_points(obs.feet, k, r, x[0], body.ankle_m())
    slots = _slots(obs)
    scale = np.where(slots >= 0, x[n_cam + np.maximum(slots, 0)] if len(x) > n_cam else 1.0, 1.0)
    span = body.head_m(obs.head_share) - body.ankle_m()
    if travel is not None:
        moving = np.any(travel != 0.0, axis=1)
        if body.walking_ankle_rise_m:
            ground = ground_points(obs.feet, k, r, x[0], body.ankle_m() + body.walking_ankle_rise_m * moving)
        ground[:, :2] += x[n_cam - 1] * travel
        span = span - (body.walking_ankle_rise_m + body.walking_head_drop_m) * moving
    ground[:, 2] += span * scale
    return project(ground, k, r, x[0])


def _slots(obs: Observations) -> np.ndarray:
    """(N,) each person-image's track as 0..J-1, -1 where unknown."""
    slots = np.full(len(obs), -1)
    known = obs.tracks >= 0
    slots[known] = np.unique(obs.tracks[known], return_inverse=True)[1]
    return slots


def _residuals(x: np.ndarray, obs: Observations, body: BodyModel, centre: tuple[float, float],
               focal: float | None, travel: np.ndarray | None = None) -> np.ndarray:
    """Whitened misfits: (u, v) per person-image, then one prior term per track's height scale."""
    span = np.maximum(obs.feet[:, 1] - obs.heads[:, 1], 1.0)
    spread = np.where(obs.tracks >= 0, WITHIN_PERSON_SPAN_STD, body.height_std_m / body.height_mean_m)
    sigma_v = np.hypot(KEYPOINT_PIXEL_STD, span * spread)
    sigma_u = np.hypot(KEYPOINT_PIXEL_STD, span * SIDEWAYS_SHARE)
    miss = (obs.heads - _predicted(x, obs, body, centre, focal, travel)) / np.stack([sigma_u, sigma_v], axis=1)
    prior = (x[_camera_count(focal, travel is not None):] - 1.0) / (body.height_std_m / body.height_mean_m)
    return np.concatenate([np.nan_to_num(miss, nan=1e3).ravel(), prior])


def _sparsity(obs: Observations, n_cam: int) -> lil_matrix:
    """Which parameters each residual depends on: the camera's, and its own track's scale."""
    slots, n = _slots(obs), len(obs)
    tracks = int(slots.max()) + 1 if n else 0
    pattern = lil_matrix((2 * n + tracks, n_cam + tracks), dtype=int)
    pattern[: 2 * n, :n_cam] = 1
    rows = np.flatnonzero(slots >= 0)
    for offset in (0, 1):
        pattern[2 * rows + offset, n_cam + slots[rows]] = 1
    pattern[2 * n + np.arange(tracks), n_cam + np.arange(tracks)] = 1
    return pattern


def _solve(x0: np.ndarray, obs: Observations, body: BodyModel, centre: tuple[float, float],
           focal: float | None, loss: str = "soft_l1", travel: np.ndarray | None = None) -> least_squares:
    walking = travel is not None
    n_cam = _camera_count(focal, walking)
    tracks = int(_slots(obs).max()) + 1 if len(obs) else 0
    forward = ([FORWARD_BOUNDS_M[0]], [FORWARD_BOUNDS_M[1]]) if walking else ([], [])
    lower = [0.2, np.radians(-30.0), np.radians(-30.0)] + ([] if focal is not None else [10.0]) + forward[0] \
        + [0.5] * tracks
    upper = [500.0, np.radians(89.0), np.radians(30.0)] + ([] if focal is not None else [1e5]) + forward[1] \
        + [1.5] * tracks
    x0 = np.concatenate([x0[:n_cam], np.zeros(n_cam - len(x0[:n_cam])), np.ones(tracks)])
    x0 = np.clip(x0, np.array(lower) + 1e-6, np.array(upper) - 1e-6)
    return least_squares(_residuals, x0, bounds=(lower, upper), loss=loss, x_scale="jac",
                         jac_sparsity=_sparsity(obs, n_cam), args=(obs, body, centre, focal, travel))


def estimate_camera(obs: Observations, size: tuple[int, int], *, focal: float | None = None,
                    centre: tuple[float, float] | None = None, body: BodyModel | None = None,
                    walking: bool = False) -> CameraEstimate:
    """A static camera (f, H, tilt, roll) fitted to people's foot and head points.

    obs: the people (:func:`pedenv.calibration.observations.observations_of`). size: (width,
    height) pixels. focal: the focal length in pixels when known (intrinsics or ``fov_deg``):
    then only H, tilt and roll are fitted. centre: the principal point (default: the image
    centre). Raises :class:`~pedenv.calibration.refusals.CalibrationRefused` with what to give
    instead when the people cannot fix the camera (too few, one row only, a level camera
    without a focal length). walking: the head keypoint is placed a fitted offset (metres,
    :data:`FORWARD_BOUNDS_M`) ahead of the feet along each track's direction of travel on the
    ground (walkers lean forward, their ankles trail the body's axis): for a static
    camera, whose tracks' ground points are the world's; without it the head is over the feet.
    """
    body = body or BodyModel()
    centre = centre if centre is not None else (size[0] / 2.0, size[1] / 2.0)
    check_spread(obs, size)
    span_world = float(np.mean(body.head_m(obs.head_share))) - body.ankle_m()
    start = closed_form(obs, centre, span_world, body.ankle_m(), focal)
    f0 = start.focal if start.focal is not None else float(size[0])  # about a 53 deg field of view
    x0 = np.array([start.height if np.isfinite(start.height) else 5.0, start.tilt, 0.0] + ([] if focal else [f0]))
    travel = _travel(x0, obs, body, centre, focal) if walking else None
    fit = _solve(x0, obs, body, centre, focal, travel=travel)
    inliers = np.abs(fit.fun[: 2 * len(obs)].reshape(-1, 2)).max(axis=1) <= OUTLIER_SIGMA
    kept = obs.subset(inliers)
    check_spread(kept, size)
    travel = _travel(fit.x, kept, body, centre, focal) if travel is not None else None
    fit = _solve(fit.x, kept, body, centre, focal, loss="linear", travel=travel)
    own = _covariance(fit, kept, focal is not None)
    h, f = fit.x[0], float(focal if focal is not None else fit.x[3])
    miss = kept.heads - _predicted(fit.x, kept, body, centre, focal, travel)
    rms = float(np.sqrt(np.nanmean(np.sum(miss ** 2, axis=1))))
    estimate = CameraEstimate(f, float(h), float(fit.x[1]), float(fit.x[2]), own, size, centre, kept.people,
                              len(kept), rms, focal is not None)
    check_result(estimate, start)  # what the people fix: the fit's own spread
    stated = own * FIT_STD_SCALE ** 2
    stated[1, 1] += (h * CROWD_MEAN_STD_M / body.height_mean_m) ** 2
    return dataclasses.replace(estimate, covariance=stated)


def _travel(x: np.ndarray, obs: Observations, body: BodyModel, centre: tuple[float, float],
            focal: float | None) -> np.ndarray | None:
    """Each person-image's direction of travel (:func:`travel_directions`) on the ground under the
    camera ``x`` (H, tilt, roll[, f], ...), held fixed while the camera is fitted (a person-image
    crossing :data:`MIN_TRAVEL_M` as the camera moves would make the misfits jump, and the
    Jacobian with them); None where nobody moves (a walker's forward offset would have nothing to
    fix it)."""
    f = focal if focal is not None else x[3]
    ground = ground_points(obs.feet, intrinsics(f, centre), camera_rotation(x[1], x[2]), x[0], body.ankle_m())
    travel = travel_directions(ground, obs)
    return travel if np.any(travel != 0.0) else None


def _inverse(information: np.ndarray) -> np.ndarray:
    """The inverse of a Fisher information matrix whose unfixed directions (a parameter the data
    do not move, as a level camera's focal length) come out with a huge variance, not zero."""
    scale = 1.0 / np.sqrt(np.maximum(np.diag(information), 1e-300))
    scaled = information * np.outer(scale, scale)
    return np.linalg.inv(scaled + UNFIXED_RIDGE * np.eye(len(scaled))) * np.outer(scale, scale)


def _covariance(fit: least_squares, obs: Observations, focal_given: bool) -> np.ndarray:
    """(4, 4) covariance of (f, H, tilt, roll) from the Jacobian of the whitened misfits (the
    people's heights marginalised), widened to the clustered (sandwich) estimate: one person's
    images share the person's gait, lean and facing, so their misfits are summed per track
    before they are counted (a person-image without a track is its own cluster)."""
    j = fit.jac.toarray() if hasattr(fit.jac, "toarray") else np.asarray(fit.jac)
    inverse = _inverse(j.T @ j)
    slots = _slots(obs)
    tracks = int(slots.max()) + 1 if len(obs) else 0
    own = np.where(slots >= 0, slots, tracks + np.arange(len(obs)))
    cluster = np.concatenate([np.repeat(own, 2), np.arange(tracks)])
    scores = np.zeros((int(cluster.max()) + 1, j.shape[1]))
    np.add.at(scores, cluster, j * fit.fun[:, None])
    clusters = len(np.unique(cluster))
    sandwich = inverse @ (scores.T @ scores) @ inverse * clusters / max(clusters - 1, 1)
    n_cam = _camera_count(1.0 if focal_given else None)  # the forward offset (after them) left out
    model, robust = inverse[:n_cam, :n_cam], sandwich[:n_cam, :n_cam]
    spread = np.sqrt(np.maximum(np.diag(model), np.diag(robust)))  # each parameter's wider 1-sigma
    scale = spread / np.sqrt(np.maximum(np.diag(model), 1e-30))
    inner = model * np.outer(scale, scale)  # the model's correlations, the wider spreads
    cov = np.zeros((4, 4))
    if focal_given:
        cov[1:, 1:] = inner
    else:
        order = [3, 0, 1, 2]
        cov[:] = inner[np.ix_(order, order)]
    return cov


def fitted_heads(estimate: CameraEstimate, obs: Observations, body: BodyModel | None = None) -> np.ndarray:
    """(N, 2) pixels: where ``estimate`` puts the head keypoints of ``obs``' people (of mean height)."""
    x = np.array([estimate.height, estimate.tilt, estimate.roll, estimate.focal])
    return _predicted(x, obs, body or BodyModel(), estimate.centre, None)
