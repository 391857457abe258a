"""A vehicle camera's mounting (height, pitch, roll) from the people it sees and the road it drives on.

The people fix the height (in units of their heights), the pitch and the roll
(:func:`pedenv.calibration.fit.estimate_camera` with the intrinsics given); the road fixes the pitch
through the direction of travel (:mod:`pedenv.calibration.road`). The two are combined with their
uncertainties: the people's estimate, a Gaussian over (height, tilt, roll), is conditioned on the
road's one constraint (the travel direction level: :meth:`RoadCue.misfit` zero within its 1-sigma),
an iterated linearised update. The people's height and tilt are correlated (a horizon placed too
high makes every person nearer and the camera lower), so a better pitch moves the height too.

Without enough people the height is not seen at all: the road alone gives the pitch, never a
mounting, and the estimate is refused in one line that says what the road gave.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.fit import BodyModel, estimate_camera
from pedenv.calibration.observations import Observations
from pedenv.calibration.refusals import CalibrationRefused
from pedenv.calibration.road import RoadCue

#: 1-sigma of the people's tilt against the road the car drives on, degrees, added to the people's own
#: (along the fit's correlations: the height and roll follow a tilt error as the fit couples them). The
#: people of a vehicle camera stand on sidewalks and crossings beside and ahead of the car, whose
#: curbs, camber and slopes are not the car's road: the people-only tilt misses the plane of the
#: labelled boxes' bottoms by 0.55 deg RMS on the KITTI drives 0013, 0004 and 0016 (skeletons rendered
#: from the labels; -0.04, +0.83, +0.45 deg), against the fit's own 0.05-0.12 deg.
PEOPLE_GROUND_TILT_STD_DEG = 0.55
#: Gauss-Newton iterations of the update (the road's constraint is nearly linear in tilt and roll
#: over the people's spread: three are many).
UPDATE_ITERATIONS = 3
#: Step of the numerical derivative of the road's misfit by tilt and roll, radians.
DERIVATIVE_STEP = 1e-6
#: What a user gives instead when the mounting cannot be estimated.
INSTEAD = "give cam_to_vehicle (the camera's height over the road and its pitch) in the --calibration YAML"


def widen_people(people: CameraEstimate) -> CameraEstimate:
    """``people``'s estimate with :data:`PEOPLE_GROUND_TILT_STD_DEG` added to its tilt's variance, the
    height's and roll's following the tilt as the fit's covariance regresses them on it."""
    cov = people.covariance.copy()
    tilt_var = cov[2, 2]
    along = cov[:, 2] / tilt_var if tilt_var > 0 else np.eye(4)[2]
    along[0] = 0.0  # the focal length is given
    cov += np.radians(PEOPLE_GROUND_TILT_STD_DEG) ** 2 * np.outer(along, along)
    return dataclasses.replace(people, covariance=cov)


def combine(people: CameraEstimate, road: RoadCue) -> CameraEstimate:
    """``people``'s estimate conditioned on ``road``: (height, tilt, roll) and their covariance
    updated; the focal length (given) stays. ``summary()`` then holds the road's own pitch and
    the disagreement of the two cues in sigmas (``road``)."""
    x0 = np.array([people.height, people.tilt, people.roll])
    p0 = people.covariance[1:, 1:]
    x = x0.copy()
    gain, jac = np.zeros(3), np.zeros(3)
    for _ in range(UPDATE_ITERATIONS):
        miss = road.misfit(x[1], x[2])
        jac = np.array([0.0,
                        (road.misfit(x[1] + DERIVATIVE_STEP, x[2]) - miss) / DERIVATIVE_STEP,
                        (road.misfit(x[1], x[2] + DERIVATIVE_STEP) - miss) / DERIVATIVE_STEP])
        innovation = float(jac @ p0 @ jac) + road.std ** 2
        gain = p0 @ jac / innovation
        x = x0 + gain * (0.0 - miss - jac @ (x0 - x))
    covariance = people.covariance.copy()
    covariance[1:, 1:] = (np.eye(3) - np.outer(gain, jac)) @ p0
    covariance[1:, 1:] = 0.5 * (covariance[1:, 1:] + covariance[1:, 1:].T)
    disagreement = road.misfit(people.tilt, people.roll) / np.sqrt(float(jac @ p0 @ jac) + road.std ** 2)
    return dataclasses.replace(people, height=float(x[0]), tilt=float(x[1]), roll=float(x[2]), covariance=covariance,
                               road={**road.summary(), "people_tilt_deg": float(np.degrees(people.tilt)),
                                     "disagreement_sigma": float(abs(disagreement))})


def estimate_mounting(people: Observations, size: tuple[int, int], *, focal: float,
                      centre: tuple[float, float] | None = None, body: BodyModel | None = None,
                      road: RoadCue | None = None) -> CameraEstimate:
    """A vehicle camera's height, tilt and roll from ``people`` and, where the car moved, ``road``.

    people: the upright people of the warm-up (:mod:`pedenv.calibration.observations`). size:
    (width, height) pixels; focal: pixels (the intrinsics or ``fov_deg`` given); centre: the
    principal point (default: the image centre); body: where the pose source puts the keypoints.
    road: the pooled travel direction (:class:`~pedenv.calibration.road.RoadCue`), None for a
    parked car. Raises :class:`~pedenv.calibration.refusals.CalibrationRefused` when the people do
    not fix the height (with or without the road: the road gives no height), naming what the road gave.
    """
    try:
        found = estimate_camera(people, size, focal=focal, centre=centre, body=body)
    except CalibrationRefused as exc:
        if road is None:
            raise
        reason = str(exc).split("; give")[0]
        raise CalibrationRefused(
            f"the camera's height cannot be estimated: {reason}; the road alone gave only the pitch "
            f"({np.degrees(road.pitch):.2f} +- {np.degrees(road.std):.2f} deg from {road.steps} steps of travel), "
            f"the height needs people; {INSTEAD}") from exc
    found = widen_people(found)
    return found if road is None else combine(found, road)
