"""The ``fused`` locator: ground contact, triangulation and height prior, gated and fused.

Per frame and vectorized over the N tracked skeletons: the skeletons' shared geometry is
computed once (:class:`~pedenv.localization.fused.cue.FrameSkeletons`); each enabled cue gives an x-y
estimate with its frame-to-frame and per-person covariances or declines with a reason;
:func:`~pedenv.localization.fused.fusion.fuse_cues` drops a cue that disagrees and fuses the rest.
The model's Kalman filter then filters the fused measurement with its frame-to-frame
covariance and adds the per-person part to what it reports. ``sources`` says which cues
made each position and why the others did not, e.g. ``ground+height;triangulation:no-baseline``.
A pedestrian no cue can place gets a wide guess from its box height (``box``).

The height cue uses each track's own body height, learned from the frames where the ground or
the triangulation placed the person too (:mod:`~pedenv.localization.fused.body_height`); the
ground cue cuts the ankle rays with the road plane raised to the scene's ground level, learned
from its people (:mod:`~pedenv.localization.fused.road_level`; not under a static camera).

The 3D skeleton: the person's shape triangulated over the track's history where the
parallax allows (a swinging limb fails the outlier test), placed at the fused position;
else each keypoint cut from its ray at the person's range.
"""

from __future__ import annotations

import numpy as np

from pedenv.config import Config
from pedenv.localization.base import FrameGeometry, Measurement
from pedenv.localization.fused.body_height import add_measurements, height_measurements, prior_std, track_heights
from pedenv.localization.fused.cue import (
    CueEstimate,
    FrameSkeletons,
    across_variance,
    horizontal_bearing,
    keypoint_usable,
    range_bearing_covariance,
)
from pedenv.localization.fused.fusion import STATIC_TRUST_ORDER, TRUST_ORDER, fuse_cues
from pedenv.localization.fused.ground import ankle_height, box_bottom_ranges, ground_cue
from pedenv.localization.fused.height import height_cue
from pedenv.localization.fused.history import HEIGHT_CUES, TORSO_KEYPOINTS, TrackHistory, ray_terms
from pedenv.localization.fused.road_level import RoadLevel, crowd_floor, people_levels
from pedenv.localization.fused.sources import CueSources
from pedenv.localization.fused.triangulation import RaysNow, Triangulated, triangulate, triangulation_cue
from pedenv.records import Frame

#: A cue whose disagreement with the others exceeds this chi-square quantile (2 dof) is
#: dropped before fusion: 0.999, so a cue within its own covariance is kept but for one
#: frame in a thousand.
GATE_PROBABILITY = 0.999
#: A pedestrian no cue can place is guessed from its box with this relative spread.
BOX_RELATIVE_STD = 0.5
#: The part of it that changes from frame to frame: a box's height moves with the pose and
#: with the detector's box edges (each off by about 3 % of the height), and so does its range.
#: Without it the filter would take each box range as exact along the ray.
BOX_FRAME_RELATIVE_STD = 0.05
#: Pixel noise (pixels) and lateral spread (metres) across the box centre's ray.
BOX_PIXEL_STD, BOX_LATERAL_STD_M = 5.0, 0.5
#: Box ranges are clipped to this interval (metres).
BOX_RANGE_M = (0.5, 500.0)
#: How far a keypoint may lie in front of or behind the body's plane facing the camera
#: (arms and legs reaching), metres: the spread of a keypoint cut at the person's range.
BODY_DEPTH_STD_M = 0.15
#: A keypoint ray this close to vertical is cut at this share of the range (no division by 0).
MIN_ALONG = 1e-3
#: Triangulation pairs only consecutive observations: a track whose newest past ray is older
#: than this many frame intervals (the shortest interval seen; 1.5 so a jittered clock still
#: counts one frame) was missed in between and leaves its past rays behind. Across a gap the
#: person walked unseen and the track's filter comes out of it wide, so one low-parallax range
#: carries it off (KITTI drive 0015 with ``tracking.max_misses`` 5: 83 m off in 7 frames;
#: rays across up to 2 missed frames measured worse there, 4.58-4.84 % against 4.10-4.12 %).
MAX_RAY_GAP_FRAMES = 1.5


def box_estimate(boxes: np.ndarray, centre_rays: np.ndarray, origin: np.ndarray, focal_px: float,
                 height_m: float, max_ranges: np.ndarray | None = None) -> CueEstimate:
    """Last resort: range ``f H / box height`` along the box centre's ray, 50 % spread
    (the person's own height and pose: per-person, 5 % of it frame-to-frame); across the ray
    frame-to-frame.

    boxes: (N, 4) pixels. centre_rays: (N, 3) unit, world. origin: (3,) world, metres.
    max_ranges: optional (N,) metres, no range beyond (a static camera: where the box's
    bottom meets the ground, :func:`~pedenv.localization.fused.ground.box_bottom_ranges`).
    """
    r = np.clip(focal_px * height_m / np.maximum(boxes[:, 3] - boxes[:, 1], 1.0), *BOX_RANGE_M)
    if max_ranges is not None:
        r = np.clip(np.minimum(r, max_ranges), *BOX_RANGE_M)
    bearing = horizontal_bearing(centre_rays)
    across = across_variance(r, focal_px, BOX_PIXEL_STD, BOX_LATERAL_STD_M)
    frame = range_bearing_covariance(bearing, (BOX_FRAME_RELATIVE_STD * r) ** 2, across)
    return CueEstimate("box", origin[:2] + r[:, None] * bearing, frame,
                       range_bearing_covariance(bearing, (BOX_RELATIVE_STD * r) ** 2, 0.0),
                       np.ones(len(r), bool), np.zeros(len(r), np.int64))


def keypoints_at_range(rays: np.ndarray, origin: np.ndarray, bearing: np.ndarray, ranges: np.ndarray) -> np.ndarray:
    """3D skeleton (N, 17, 3), world, metres: each keypoint ray (N, 17, 3) cut by the vertical
    plane facing the camera at horizontal ``ranges`` (N,) along ``bearing`` (N, 2)."""
    along = rays[..., 0] * bearing[:, None, 0] + rays[..., 1] * bearing[:, None, 1]
    return origin + (ranges[:, None] / np.maximum(along, MIN_ALONG))[..., None] * rays


def skeleton_3d(tri: Triangulated, rays: np.ndarray, origin: np.ndarray, xy: np.ndarray, bearing: np.ndarray,
                ranges: np.ndarray) -> np.ndarray:
    """(N, 17, 3) world, metres: the person's shape from triangulation placed at the fused
    ground point ``xy`` (N, 2), or each keypoint ray cut at ``ranges`` (N,) along ``bearing``
    (N, 2) (:func:`keypoints_at_range`).

    A walker's drift moves every triangulated keypoint alike, so it leaves the shape (each
    keypoint against the torso) alone: a keypoint is taken from triangulation where its
    pixel-noise variance along the bearing is below the cut's :data:`BODY_DEPTH_STD_M`,
    and the torso was triangulated; the shape is moved so the torso sits over ``xy``.
    """
    cut = keypoints_at_range(rays, origin, bearing, ranges)
    torso = tri.good[:, TORSO_KEYPOINTS]
    count = torso.sum(axis=1)
    if not count.any():
        return cut
    centre = (np.where(torso[..., None], tri.points[:, TORSO_KEYPOINTS, :2], 0.0)).sum(axis=1) / np.maximum(count, 1)[
        :, None
    ]
    bx, by = bearing[:, None, 0], bearing[:, None, 1]
    c = tri.covariances
    var = c[..., 0] * bx * bx + 2.0 * c[..., 1] * bx * by + c[..., 2] * by * by
    better = tri.good & (count > 0)[:, None] & (var < BODY_DEPTH_STD_M**2)
    placed = tri.points.copy()
    placed[..., :2] += (xy - centre)[:, None, :]
    return np.where(better[..., None], placed, cut)


class FusedLocator:
    """The ``fused`` position method (``Config.fused``), one :class:`Measurement` per frame.

    Its per-track memory (``columns``) is the :class:`TrackHistory`. ``last_cues``: the last
    frame's cue estimates, one row per pedestrian of its measurement (what
    ``benchmarks/kitti_position_breakdown.py`` scores each cue by) and ``last_heights``: the
    body height each one's height cue took (its track's); read-only.
    """

    def __init__(self, config: Config) -> None:
        self.config = config
        self.max_range_m = config.fused.max_range_m  # the model clamps beyond (pedenv.localization.bounds)
        self.columns = self.history = TrackHistory(config.fused.history_length)
        self.last_cues: list[CueEstimate] = []
        self.last_heights = np.zeros(0)  # the body height (m) the last frame's height cue took per pedestrian
        self.road = RoadLevel()
        self._last_time, self._frame_dt = -np.inf, np.inf  # the last frame's time, the shortest interval (s)

    def locate(self, geo: FrameGeometry, rows: np.ndarray) -> Measurement:
        cfg, frame, det = self.config.fused, geo.frame, geo.detections
        cam, h = frame.camera, self.history
        focal = float(cam.intrinsics[0, 0])
        rays, origin = geo.rays, geo.origin
        usable = keypoint_usable(det.keypoints, det.confidences, cam.width, cam.height, cfg.min_keypoint_confidence)
        skel = FrameSkeletons.of(rays, origin, usable, cfg.keypoint_pixel_std / focal)
        placed = h.placed[rows]
        last = h.positions[rows] - origin[:2]
        last_range = np.where(placed, np.sqrt(last[:, 0] ** 2 + last[:, 1] ** 2), np.nan)

        cues: list[CueEstimate] = []
        level, level_var = (0.0, 0.0) if cam.static else self.road.estimate(
            crowd_floor(self._camera_height(frame, origin), cfg.person_height_mean_m))
        if "ground" in cfg.cues:
            cues.append(ground_cue(frame, skel, cfg, level, level_var))
        heights = track_heights(h.height_sums[rows], cfg)
        self.last_heights = heights[0]
        if "height" in cfg.cues:
            cues.append(height_cue(skel, cfg, *heights, reference_range=last_range))
        terms, dots = ray_terms(rays, origin)
        # where each keypoint was: the track's last skeleton, moved onto this frame's rays
        last_skel = h.skeletons[rows]
        depth = ((last_skel - origin) * rays).sum(-1)
        start = origin + np.where(placed[:, None], np.maximum(depth, MIN_ALONG), 1.0)[..., None] * rays
        now = RaysNow(rays, terms, usable, origin, frame.timestamp, skel.noise)
        h.forget_before_gap(rows, self._gap_start(frame.timestamp))
        tri = triangulate(now, start, placed, h.of(rows))
        h.push(rows, rays, terms, dots, usable, origin, frame.timestamp)
        if "triangulation" in cfg.cues:
            cues.append(triangulation_cue(tri, skel))
        fused = fuse_cues(cues, GATE_PROBABILITY, origin[:2], STATIC_TRUST_ORDER if cam.static else TRUST_ORDER)
        sources = CueSources.of(cues, fused, ~fused.valid).spell()
        self.last_cues = cues
        if not cam.static:  # a static camera's calibrated ground is trusted first (STATIC_TRUST_ORDER)
            self._learn_heights(rows, origin, heights)
            self._learn_level(frame, origin, heights[0], level)

        xy, cov, bias = fused.positions, fused.covariances, fused.bias_covariances
        if not fused.valid.all():
            bound = box_bottom_ranges(frame, det.boxes, origin) if cam.static else None
            box = box_estimate(det.boxes, geo.centre_rays, origin, focal, cfg.person_height_mean_m, bound)
            lost = ~fused.valid
            xy = np.where(lost[:, None], box.positions, xy)
            cov = np.where(lost[:, None, None], box.covariances, cov)
            bias = np.where(lost[:, None, None], box.bias_covariances, bias)

        positions = np.column_stack([xy, road_height(frame.ego.rotation, frame.ego.translation, xy)])
        offset = xy - origin[:2]
        ranges = np.sqrt(offset[:, 0] ** 2 + offset[:, 1] ** 2)
        bearing = offset / np.maximum(ranges, MIN_ALONG)[:, None]
        skeleton = skeleton_3d(tri, rays, origin, xy, bearing, ranges)
        h.place(rows, xy, skeleton, fused.valid)
        return Measurement(positions, cov, sources, skeleton, bias)

    def _learn_heights(self, rows: np.ndarray, origin: np.ndarray, heights: tuple[np.ndarray, np.ndarray]) -> None:
        """Add this frame's body-height measurements of the tracks at ``rows`` (N,) to their
        sums: each cue of :data:`HEIGHT_CUES` against the height cue (placed with ``heights``,
        the tracks' height and spread, metres)."""
        by_name = {q.name: q for q in self.last_cues}
        if "height" not in by_name:
            return
        sums = self.history.height_sums
        for c, name in enumerate(HEIGHT_CUES):
            if name in by_name:
                measured = height_measurements(by_name["height"], by_name[name], origin, heights[0])
                sums[rows, c] = add_measurements(sums[rows, c], *heights, measured)

    def _learn_level(self, frame: Frame, origin: np.ndarray, used_heights: np.ndarray, level: float) -> None:
        """Add this frame's people to the scene's ground level (:mod:`~pedenv.localization.fused.road_level`):
        where the height cue (placed with ``used_heights`` (N,) metres) puts the feet above the
        plane the ground cue used (raised by ``level`` metres)."""
        by_name = {q.name: q for q in self.last_cues}
        if "height" not in by_name or "ground" not in by_name:
            return
        cfg = self.config.fused
        camera_height = self._camera_height(frame, origin) - level
        levels, variances = people_levels(by_name["height"], by_name["ground"], origin, used_heights,
                                          cfg.person_height_mean_m, (prior_std(cfg) / cfg.person_height_mean_m) ** 2,
                                          camera_height)
        self.road.update(frame.timestamp, levels + level, variances)

    def _camera_height(self, frame: Frame, origin: np.ndarray) -> float:
        """Metres: the camera centre ``origin`` (3,) above the vehicle's road plane lifted by the
        ankle keypoint's resting height (the plane the ground cue cuts before any level)."""
        normal = frame.ego.rotation[:, 2]
        return float(normal @ origin - normal @ frame.ego.translation) - ankle_height(self.config.fused)

    def _gap_start(self, time: float) -> float:
        """The time (seconds) a track's newest past ray must reach at this frame's ``time``
        (:data:`MAX_RAY_GAP_FRAMES` frame intervals back; -inf until an interval is known)."""
        if time > self._last_time:
            self._frame_dt = min(self._frame_dt, time - self._last_time)
        self._last_time = time
        return time - MAX_RAY_GAP_FRAMES * self._frame_dt


def road_height(rotation: np.ndarray, translation: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """World z (N,) of the vehicle's road plane (vehicle z = 0) at world ``xy`` (N, 2), metres."""
    normal = rotation[:, 2]
    return translation[2] - ((xy - translation[:2]) @ normal[:2]) / max(normal[2], 1e-6)
