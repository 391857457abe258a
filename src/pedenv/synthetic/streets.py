"""Street layouts and the pedestrians placed on them: sidewalk walkers, crossers, standers.

A :class:`Road` is a straight street given by a point on its centre line and its
direction; positions on it are (along, across) in metres, across positive to the left
of the road's direction. Sidewalks run beside the carriageway on both sides.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.synthetic.population import Pedestrians, make_group

#: How far a sidewalk walker's path reaches (metres): longer than any scene walks.
PATH_LENGTH_M = 400.0


@dataclass(frozen=True)
class Road:
    """A straight street.

    origin: (2,) world x-y, metres, on the centre line. yaw: direction in radians.
    half_width_m: centre line to kerb. sidewalk_m: width of each sidewalk.
    """

    origin: tuple[float, float] = (0.0, 0.0)
    yaw: float = 0.0
    half_width_m: float = 5.0
    sidewalk_m: float = 4.0

    @property
    def direction(self) -> np.ndarray:
        return np.array([np.cos(self.yaw), np.sin(self.yaw)])

    @property
    def normal(self) -> np.ndarray:
        """Unit vector to the left of the road's direction."""
        return np.array([-np.sin(self.yaw), np.cos(self.yaw)])

    def point(self, along: np.ndarray, across: np.ndarray) -> np.ndarray:
        """World x-y of road coordinates: along (...), across (...) metres -> (..., 2)."""
        along, across = np.asarray(along, float)[..., None], np.asarray(across, float)[..., None]
        return np.asarray(self.origin, float) + along * self.direction + across * self.normal

    def sidewalk_offsets(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """(n,) across offsets on a random side, kept 0.5 m off the kerb and the wall."""
        side = rng.choice([-1.0, 1.0], n)
        return side * (self.half_width_m + rng.uniform(0.5, self.sidewalk_m - 0.5, n))


def sidewalk_walkers(rng: np.random.Generator, road: Road, n: int, along_range: tuple[float, float], *,
                     standing_share: float = 0.1) -> Pedestrians:
    """``n`` pedestrians spread uniformly over ``along_range`` of both sidewalks.

    Walkers go either way along the sidewalk; a ``standing_share`` of them stand still,
    facing a random direction.
    """
    along = rng.uniform(*along_range, n)
    across = road.sidewalk_offsets(rng, n)
    sign = rng.choice([-1.0, 1.0], n)
    start = road.point(along, across)
    standing = rng.random(n) < standing_share
    facing = road.yaw + np.where(standing, rng.uniform(-np.pi, np.pi, n), np.where(sign > 0, 0.0, np.pi))
    length = np.where(standing, 1.0, PATH_LENGTH_M)
    end = start + length[:, None] * np.stack([np.cos(facing), np.sin(facing)], axis=1)
    return make_group(rng, np.stack([start, end], axis=1), walking=~standing)


def crossers(rng: np.random.Generator, road: Road, n: int, along_range: tuple[float, float],
             start_range_s: tuple[float, float]) -> Pedestrians:
    """``n`` pedestrians crossing ``road`` between ``along_range`` (a crosswalk or mid-block).

    Each waits at the kerb until its start time, drawn from ``start_range_s`` (negative
    times: already on the way when the scene begins), crosses, then walks on along the
    far sidewalk.
    """
    along = rng.uniform(min(along_range), max(along_range), n)
    side = rng.choice([-1.0, 1.0], n)
    kerb = road.half_width_m + rng.uniform(0.3, 1.5, n)
    turn = rng.choice([-1.0, 1.0], n) * PATH_LENGTH_M / 4
    starts = rng.uniform(*start_range_s, n)
    waypoints = np.stack([road.point(along, -side * kerb), road.point(along, side * kerb),
                          road.point(along + turn, side * kerb)], axis=1)
    # a negative start time means the crossing began before the scene: start part-way
    return _with_head_start(make_group(rng, waypoints, start_times=np.maximum(starts, 0.0)), starts)


def _with_head_start(group: Pedestrians, starts: np.ndarray) -> Pedestrians:
    """Move pedestrians whose start time is negative along their path by the time already walked."""
    offsets = group.speeds * np.maximum(-starts, 0.0)
    return Pedestrians(group.waypoints, group.speeds, group.start_times, offsets, group.heights,
                       group.phases, group.sway_phases)


def standing_group(
    rng: np.random.Generator, centres: np.ndarray, sizes: np.ndarray, *, spread_m: float = 0.8
) -> Pedestrians:
    """Clusters of standing people: ``sizes[i]`` people within ``spread_m`` of ``centres[i]`` (world x-y).

    Members of a cluster face its centre, as people chatting do.
    """
    centres = np.asarray(centres, float).reshape(-1, 2)
    where = np.repeat(centres, sizes, axis=0)
    n = where.shape[0]
    angle = rng.uniform(-np.pi, np.pi, n)
    radius = spread_m * np.sqrt(rng.uniform(0.2, 1.0, n))
    start = where + radius[:, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    facing = angle + np.pi + rng.normal(0.0, 0.3, n)
    end = start + np.stack([np.cos(facing), np.sin(facing)], axis=1)
    return make_group(rng, np.stack([start, end], axis=1), walking=False)


def plaza_walkers(rng: np.random.Generator, n: int, x_range: tuple[float, float], y_range: tuple[float, float],
                  legs: int = 4) -> Pedestrians:
    """``n`` pedestrians wandering between random points of a rectangular square (world x-y)."""
    pts = np.stack([rng.uniform(*x_range, (n, legs + 1)), rng.uniform(*y_range, (n, legs + 1))], axis=2)
    group = make_group(rng, pts)
    return Pedestrians(group.waypoints, group.speeds, group.start_times, rng.uniform(0.0, 10.0, n),
                       group.heights, group.phases, group.sway_phases)
