"""The level of the ground people stand on, above the vehicle's road plane, shared by a scene.

The ground cue cuts the stance ankle's ray with the vehicle's road plane; where people stand on
a raised pavement (0.1-0.3 m), or the road ahead rises, every one of them is placed too far, by
the same share of the range (``dz / camera height``), and a body height measured from their feet
(:mod:`~pedenv.localization.fused.body_height`) comes out too tall by the same share. One person
cannot tell a raised pavement from being tall; many can: their heights scatter about the
population's mean, so the level at which the height cue (at the population's mean height) puts
their feet, averaged over the people of the last seconds, is where the ground under them is. The
ground cue then cuts the rays with the plane lifted by that level.

For each person placed by both cues the height cue's range ``r_h`` (at the mean height) and the
ground cue's ``r_g`` say the feet lie ``c (1 - r_h / r_g)`` above the plane used (``c`` the camera's
height above it): a measurement of the level whose spread is the height prior's share of ``c`` (about
9 cm) plus the frame's noise of both ranges. Each frame's people add their information, which
decays over :data:`MEMORY_S` (a moving car leaves the pavement behind); the level starts at 0 with
spread :data:`PRIOR_STD_M`. The ground cue's per-person spread (``ROAD_HEIGHT_STD_M``, the road
under one person against the rest) stays as it was. A static camera's ground is its calibrated
plane and keeps no level.

The level rests on the people's mean height being the population's, and a scene's people may all
be tall (the parked KITTI drive 0016, whose people average 1.85 m): however many are seen, their
mean level is off by the crowd's mean height (:data:`pedenv.body.CROWD_MEAN_STD_M`, :func:`crowd_floor`), so
it is fused with the prior with that floor in its variance (:meth:`RoadLevel.estimate`) and moves
the plane only part of the way; the level's error from the people goes into the ground cue's
per-person covariance (and so into its weight in the fusion and into the track heights learned
from it).
"""

from __future__ import annotations

import numpy as np

from pedenv.body import CROWD_MEAN_STD_M
from pedenv.localization.fused.body_height import along_variance
from pedenv.localization.fused.cue import CueEstimate
from pedenv.localization.fused.ground import ROAD_HEIGHT_STD_M

#: Spread (metres, 1 sigma) of the level before any person is seen: the ground cue's own spread of
#: the road under a person about the vehicle's plane (``ROAD_HEIGHT_STD_M``, kerbs and camber); a
#: wider prior (0.15 m, a kerb's height) lets a crowd taller than the population raise the level
#: further than the ground cue itself allows the road to be off (the parked KITTI drive 0016).
PRIOR_STD_M = ROAD_HEIGHT_STD_M
#: The people's information on the level decays by ``e`` over this many seconds: about a block at
#: city speed, long enough to average a dozen people, short enough to follow the street.
MEMORY_S = 10.0
#: The level is kept within this many metres of the vehicle's plane (a step or a slope beyond
#: is not one level under the scene's people).
MAX_LEVEL_M = 0.5


class RoadLevel:
    """The scene's ground level above the vehicle's road plane (metres) and what it rests on.

    information: 1/m^2, the people's summed (decayed) information; weighted: m/m^2, their
    information-weighted levels; time: seconds of the last update (None before any).
    """

    def __init__(self) -> None:
        self.information, self.weighted = 0.0, 0.0
        self.time: float | None = None

    @property
    def level(self) -> float:
        """Metres above the vehicle's road plane: the people's level shrunk towards 0 by the
        prior (no crowd floor; :meth:`estimate` with one)."""
        return self.estimate(0.0)[0]

    def estimate(self, floor_m: float) -> tuple[float, float]:
        """(metres, m^2): the level and the variance it adds to the ground under a person.

        The people's mean level ``L`` is off by their noise (``1 / information``) and by
        ``floor_m`` metres (1 sigma) common to all of them (:func:`crowd_floor`); fused with the
        prior ``N(0, PRIOR_STD_M^2)`` it is ``k L``, ``k = P / (P + 1 / information + floor^2)``.
        The road's own spread about the vehicle's plane (``ROAD_HEIGHT_STD_M``) stays in the
        ground cue; what the level adds is its error from the people, ``k^2 (1 / information +
        floor^2)`` (0 before anyone is seen, when the plane is not moved)."""
        i, prior, floor = self.information, PRIOR_STD_M**2, float(floor_m) ** 2
        denominator = prior * i + 1.0 + i * floor
        level = float(np.clip(self.weighted * prior / denominator, -MAX_LEVEL_M, MAX_LEVEL_M))
        return level, prior**2 * i * (1.0 + i * floor) / denominator**2

    def update(self, time: float, levels: np.ndarray, variances: np.ndarray) -> None:
        """Decay to ``time`` (seconds), then add the people's measured ``levels`` (M,) metres
        with their ``variances`` (M,) m^2. A time before the last one starts a new scene:
        what was learned is forgotten."""
        if self.time is not None and time < self.time:
            self.information, self.weighted = 0.0, 0.0
        elif self.time is not None and time > self.time:
            keep = float(np.exp(-(time - self.time) / MEMORY_S))
            self.information *= keep
            self.weighted *= keep
        self.time = time
        w = 1.0 / np.asarray(variances, float)
        self.information += float(w.sum())
        self.weighted += float((w * np.asarray(levels, float)).sum())


def crowd_floor(camera_height: float, mean_height: float) -> float:
    """Metres: how far the level may be off however many people are seen, the crowd's unknown
    mean height (:data:`pedenv.body.CROWD_MEAN_STD_M`) as a share of ``mean_height`` (metres) times the
    ``camera_height`` (metres above the plane)."""
    return float(camera_height) * CROWD_MEAN_STD_M / float(mean_height)


def people_levels(height: CueEstimate, ground: CueEstimate, origin: np.ndarray, used_heights: np.ndarray,
                  mean_height: float, prior_rel_var: float, camera_height: float) -> tuple[np.ndarray, np.ndarray]:
    """(M,) metres and (M,) m^2: the levels of the M people both cues placed this frame
    (:func:`level_measurements`). height: the height cue, placed with ``used_heights`` (N,)
    metres; its ranges are scaled to the population's ``mean_height`` (metres, relative spread
    ``prior_rel_var``). origin: (3,) camera centre, world, metres. camera_height: metres above
    the plane the ground cue used."""
    both = height.valid & ground.valid
    if not both.any():
        return np.zeros(0), np.zeros(0)
    offset = height.positions[both] - origin[:2]
    r_h = np.sqrt((offset**2).sum(1))
    bearing = offset / np.maximum(r_h, 1e-9)[:, None]
    r_g = ((ground.positions[both] - origin[:2]) * bearing).sum(1)
    ok = (r_h > 0) & (r_g > 0)
    h_rel = along_variance(height.covariances[both], bearing) / r_h**2 + prior_rel_var
    g_rel = along_variance(ground.covariances[both], bearing) / np.where(ok, r_g, 1.0) ** 2
    r_mean = r_h * mean_height / used_heights[both]
    levels, variances = level_measurements(r_mean[ok], h_rel[ok], r_g[ok], g_rel[ok], camera_height, ROAD_HEIGHT_STD_M)
    return levels, variances


def level_measurements(height_ranges: np.ndarray, height_rel_var: np.ndarray, ground_ranges: np.ndarray,
                       ground_rel_var: np.ndarray, camera_height: float,
                       road_std: float) -> tuple[np.ndarray, np.ndarray]:
    """(M,) metres and (M,) m^2: how far M people's feet lie above the plane the ground cue used.

    height_ranges: (M,) metres, the height cue's ranges at the population's mean height, with
    ``height_rel_var`` (M,) their relative variance (the height prior and the frame's noise).
    ground_ranges: (M,) metres, the ground cue's ranges along the same rays, ``ground_rel_var``
    (M,) their relative frame-to-frame variance. camera_height: metres above the plane used.
    road_std: metres, the road's own spread under one person.
    """
    ratio = height_ranges / ground_ranges
    levels = camera_height * (1.0 - ratio)
    return levels, (camera_height * ratio) ** 2 * (height_rel_var + ground_rel_var) + road_std**2
