"""A vehicle camera's mounting (height, pitch, roll) from the people it sees and the road it drives on.

The people fix the height (in units of their heights), the pitch and the roll
(:func:`pedenv.calibration.fit.estimate_camera` with the intrinsics given); the road fixes the pitch
through the direction of travel (:mod:`pedenv.calibration.road`). The two are combined with their
uncertainties: the people's estimate, a Gaussian over (height, tilt, roll), is conditioned on the
road's one constraint (the travel direction level: :meth:`RoadCue.misfit` zero within its 1-sigma),
an iterated linearised update. The people's own spread is widened first by how far the ground they
stand on (sidewalks, curbs, camber) may lie from the car's road, and the roll is held near zero by
the mounting's prior (a vehicle camera is mounted level across the car; the people's roll is mostly
their ground's sideways slope). The people's height and
tilt are correlated (a horizon placed too high makes every person nearer and the camera lower),
so a better pitch moves the height too.

Where the ego poses give the steps' metric lengths, the road's scale gives the height in metres
(:class:`~pedenv.calibration.road.RoadScale`), independently of the people's heights: the estimate
is then conditioned on it too (a Gaussian update on the height, the tilt and roll following through
their correlation). With the road's pitch and scale the mounting stands without people (the roll
then the mounting's prior). Without ego poses and without enough people the height is not seen at
all: the road alone gives the pitch, never a mounting, and the estimate is refused in one line that
says what the road gave.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.fit import BodyModel, estimate_camera
from pedenv.calibration.observations import Observations
from pedenv.calibration.refusals import CalibrationRefused
from pedenv.calibration.road import RoadCue, RoadScale

#: 1-sigma of the people's tilt against the road the car drives on, degrees, added to the people's own
#: (along the fit's correlation: the height follows a tilt error as the fit couples them). The
#: people of a vehicle camera stand on sidewalks and crossings beside and ahead of the car, whose
#: curbs, camber and slopes are not the car's road: the people-only tilt misses the plane of the
#: labelled boxes' bottoms by 0.55 deg RMS on the KITTI drives 0013, 0004 and 0016 (skeletons rendered
#: from the labels; -0.04, +0.83, +0.45 deg), against the fit's own 0.05-0.12 deg.
PEOPLE_GROUND_TILT_STD_DEG = 0.55
#: The same for the people's roll, degrees: people on a sidewalk to one side, a curb higher than the
#: road, tip the plane they stand on sideways. On the same drives the people-only roll misses KITTI's
#: calibrated roll of the camera (-0.24 and -0.11 deg against its GPS/IMU) by +0.40, +1.82, +0.02 deg
#: (1.08 RMS), against the fit's own 0.09-0.38 deg.
PEOPLE_GROUND_ROLL_STD_DEG = 1.1
#: A vehicle camera is mounted level across the car: its roll's prior is 0 with this 1-sigma, degrees
#: (the RMS of the calibrated roll of KITTI's two colour-camera calibrations, -0.24 and -0.11 deg, and
#: of nuScenes 0061's five cameras, 0.12 to 0.62 deg, against their vehicle frames: 0.35 deg).
MOUNT_ROLL_STD_DEG = 0.35
#: Gauss-Newton iterations of an update (the road's constraint is nearly linear in tilt and roll
#: over the people's spread: three are many).
UPDATE_ITERATIONS = 3
#: Step of the numerical derivative of a constraint by tilt and roll, radians.
DERIVATIVE_STEP = 1e-6
#: What a user gives instead when the mounting cannot be estimated.
INSTEAD = "give cam_to_vehicle (the camera's height over the road and its pitch) in the --calibration YAML"


def widen_people(people: CameraEstimate) -> CameraEstimate:
    """``people``'s estimate with :data:`PEOPLE_GROUND_TILT_STD_DEG` added to its tilt's variance (the
    height following the tilt as the fit's covariance regresses it on the tilt; the focal length, given,
    stays) and :data:`PEOPLE_GROUND_ROLL_STD_DEG` to its roll's."""
    cov = people.covariance.copy()
    var = people.covariance[2, 2]
    along = people.covariance[:, 2] / var if var > 0 else np.eye(4)[2]
    along[0] = along[3] = 0.0
    cov += np.radians(PEOPLE_GROUND_TILT_STD_DEG) ** 2 * np.outer(along, along)
    cov[3, 3] += np.radians(PEOPLE_GROUND_ROLL_STD_DEG) ** 2
    return dataclasses.replace(people, covariance=cov)


def condition(estimate: CameraEstimate, misfit: Callable[[float, float], float],
              std: float) -> tuple[CameraEstimate, float]:
    """``estimate`` conditioned on one constraint ``misfit(tilt, roll) = 0`` (radians) of 1-sigma ``std``
    (radians): (height, tilt, roll) and their covariance updated (an iterated linearised Gaussian update),
    and how far the estimate was from the constraint before, in sigmas of both."""
    x0 = np.array([estimate.height, estimate.tilt, estimate.roll])
    p0 = estimate.covariance[1:, 1:]
    x = x0.copy()
    gain, jac = np.zeros(3), np.zeros(3)
    for _ in range(UPDATE_ITERATIONS):
        miss = misfit(x[1], x[2])
        jac = np.array([0.0, (misfit(x[1] + DERIVATIVE_STEP, x[2]) - miss) / DERIVATIVE_STEP,
                        (misfit(x[1], x[2] + DERIVATIVE_STEP) - miss) / DERIVATIVE_STEP])
        gain = p0 @ jac / (float(jac @ p0 @ jac) + std ** 2)
        x = x0 + gain * (0.0 - miss - jac @ (x0 - x))
    covariance = estimate.covariance.copy()
    updated = (np.eye(3) - np.outer(gain, jac)) @ p0
    covariance[1:, 1:] = 0.5 * (updated + updated.T)
    apart = abs(misfit(estimate.tilt, estimate.roll)) / np.sqrt(float(jac @ p0 @ jac) + std ** 2)
    return dataclasses.replace(estimate, height=float(x[0]), tilt=float(x[1]), roll=float(x[2]),
                               covariance=covariance), float(apart)


def level_roll(people: CameraEstimate) -> CameraEstimate:
    """``people``'s estimate with its roll combined with the mounting's prior (0,
    :data:`MOUNT_ROLL_STD_DEG`). The people's roll is mostly the sideways slope of the ground they stand
    on (a sidewalk higher than the road), not the camera's: the roll is combined alone, and its link
    to the height and tilt dropped, so the people's horizon (height, tilt) stays as they fitted it."""
    cov = people.covariance.copy()
    prior = np.radians(MOUNT_ROLL_STD_DEG) ** 2
    var = cov[3, 3] * prior / (cov[3, 3] + prior)
    roll = people.roll * prior / (cov[3, 3] + prior)
    cov[3, :] = cov[:, 3] = 0.0
    cov[3, 3] = var
    return dataclasses.replace(people, roll=float(roll), covariance=cov)


def combine(people: CameraEstimate, road: RoadCue) -> CameraEstimate:
    """``people``'s estimate conditioned on ``road`` (its travel direction level, :meth:`RoadCue.misfit`
    zero within ``road.std``). ``summary()`` then holds the road's own pitch, the people's tilt and the
    disagreement of the two in sigmas (``road``)."""
    both, apart = condition(people, road.misfit, road.std)
    return dataclasses.replace(both, road={**road.summary(), "people_tilt_deg": float(np.degrees(people.tilt)),
                                           "disagreement_sigma": apart})


def scaled(estimate: CameraEstimate, scale: RoadScale) -> CameraEstimate:
    """``estimate`` conditioned on the road's scale: its height measured as ``scale.height`` within
    ``scale.std`` (a linear Gaussian update; tilt and roll follow through their correlation with it).
    ``road`` in ``summary()`` then holds the scale's summary (``scale``), the people's height and the
    disagreement in sigmas (``height_disagreement_sigma``)."""
    x = np.array([estimate.height, estimate.tilt, estimate.roll])
    p = estimate.covariance[1:, 1:]
    total = float(p[0, 0]) + scale.std ** 2
    gain = p[:, 0] / total
    x = x + gain * (scale.height - x[0])
    covariance = estimate.covariance.copy()
    updated = p - np.outer(gain, p[0])
    covariance[1:, 1:] = 0.5 * (updated + updated.T)
    road = {**(estimate.road or {}), "scale": scale.summary(), "people_height_m": estimate.height,
            "height_disagreement_sigma": abs(scale.height - estimate.height) / np.sqrt(total)}
    return dataclasses.replace(estimate, height=float(x[0]), tilt=float(x[1]), roll=float(x[2]),
                               covariance=covariance, road=road)


def road_mounting(road: RoadCue, scale: RoadScale, size: tuple[int, int], focal: float,
                  centre: tuple[float, float]) -> CameraEstimate:
    """The mounting from the road alone: the height its scale gives, the pitch its direction of travel
    gives, the roll the mounting's prior (0 within :data:`MOUNT_ROLL_STD_DEG`); no people."""
    cov = np.diag([0.0, scale.std ** 2, road.std ** 2, np.radians(MOUNT_ROLL_STD_DEG) ** 2])
    return CameraEstimate(focal, scale.height, road.pitch, 0.0, cov, size, centre, 0, 0, 0.0, True,
                          {**road.summary(), "scale": scale.summary()})


def estimate_mounting(people: Observations, size: tuple[int, int], *, focal: float,
                      centre: tuple[float, float] | None = None, body: BodyModel | None = None,
                      road: RoadCue | None = None, scale: RoadScale | None = None) -> CameraEstimate:
    """A vehicle camera's height, tilt and roll from ``people`` and, where the car moved, ``road``
    and (ego poses given) ``scale``.

    people: the upright people of the warm-up (:mod:`pedenv.calibration.observations`). size:
    (width, height) pixels; focal: pixels (the intrinsics or ``fov_deg`` given); centre: the
    principal point (default: the image centre); body: where the pose source puts the keypoints.
    road: the pooled travel direction (:class:`~pedenv.calibration.road.RoadCue`), None for a
    parked car; scale: the road's height from the ego poses' step lengths
    (:class:`~pedenv.calibration.road.RoadScale`), None without ego poses. Raises
    :class:`~pedenv.calibration.refusals.CalibrationRefused` when nothing fixes the height (too few
    people and no road scale), naming what the road gave.
    """
    try:
        found = estimate_camera(people, size, focal=focal, centre=centre, body=body)
    except CalibrationRefused as exc:
        if road is not None and scale is not None:
            return road_mounting(road, scale, size, focal, centre if centre is not None else (size[0] / 2, size[1] / 2))
        if road is None:
            raise
        reason = str(exc).split("; give")[0]
        raise CalibrationRefused(
            f"the camera's height cannot be estimated: {reason}; the road alone gave only the pitch "
            f"({np.degrees(road.pitch):.2f} +- {np.degrees(road.std):.2f} deg from {road.steps} steps of travel), "
            f"the height needs people or the ego poses (--ego-poses: the road's scale); {INSTEAD}") from exc
    found = level_roll(widen_people(found))
    found = found if road is None else combine(found, road)
    return found if scale is None else scaled(found, scale)
