"""When people cannot fix the camera: one clear line saying what is missing and what to give instead."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pedenv.errors import InputError

if TYPE_CHECKING:
    from pedenv.calibration.estimate import CameraEstimate
    from pedenv.calibration.initial import Start
    from pedenv.calibration.observations import Observations

#: Fewest distinct upright people, and person-images, a fit takes: the height rests on the
#: mean of the people's heights, whose spread (0.09 m) over 5 people is 2.3 %.
MIN_PEOPLE, MIN_OBSERVATIONS = 5, 20
#: Least spread (standard deviation) of the feet's rows, as a share of the image height: the
#: horizon is where the people's spans, extrapolated along the rows, vanish.
MIN_ROW_SPREAD = 0.03
#: Largest 1-sigma of an estimated focal length, as a share of it, that is written out: above
#: it (a camera looking about level from people's height) the people do not fix it.
MAX_FOCAL_RELATIVE_STD = 0.1
#: Largest 1-sigma of the estimated height as a share of it.
MAX_HEIGHT_RELATIVE_STD = 0.15

INSTEAD = "give --calibration (a calibration YAML; width, height and fov_deg are enough for the focal length)"


class CalibrationRefused(InputError):
    """The people seen cannot fix the camera; the message says why and what to give instead."""


def check_spread(obs: Observations, size: tuple[int, int]) -> None:
    """Refuse too few people, or people whose feet all lie in one row."""
    if len(obs) < MIN_OBSERVATIONS or obs.people < MIN_PEOPLE:
        raise CalibrationRefused(f"too few upright people to estimate the camera: {len(obs)} person-images of "
                                 f"about {obs.people} people (at least {MIN_OBSERVATIONS} of {MIN_PEOPLE} needed); "
                                 f"{INSTEAD}, or a longer warm-up")
    spread = float(np.std(obs.feet[:, 1]))
    if spread < MIN_ROW_SPREAD * size[1]:
        raise CalibrationRefused(f"the people's feet lie in one row (rows spread {spread:.0f} px, at least "
                                 f"{MIN_ROW_SPREAD * size[1]:.0f} needed): the horizon cannot be fitted; {INSTEAD}")


def check_result(estimate: CameraEstimate, start: Start) -> None:
    """Refuse a focal length or height the people do not fix: ``estimate``'s covariance is the fit's
    own (before :data:`pedenv.calibration.fit.FIT_STD_SCALE` and the crowd's mean height widen it)."""
    f_std, h_std = estimate.std[0], estimate.std[1]
    if not estimate.focal_given and (start.focal is None or f_std > MAX_FOCAL_RELATIVE_STD * estimate.focal):
        raise CalibrationRefused(
            "the people's feet-to-head lines are too close to parallel to fix the focal length (a camera looking "
            f"about level, or a narrow field of view; 1-sigma {min(f_std / estimate.focal, 99.0):.0%}); give fov_deg, "
            "the horizontal field of view, with width and height in a --calibration YAML")
    if not np.isfinite(h_std) or h_std > MAX_HEIGHT_RELATIVE_STD * estimate.height:
        raise CalibrationRefused(f"the people do not fix the camera's height ({estimate.height:.2f} m, 1-sigma "
                                 f"{h_std:.2f} m); {INSTEAD}")
