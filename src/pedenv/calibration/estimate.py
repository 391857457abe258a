"""The estimated camera: parameters, their covariance, and what they rest on."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.calibration.geometry import static_camera
from pedenv.records import Camera

#: The parameters in the order of :attr:`CameraEstimate.covariance`, with their units.
PARAMETERS = (("focal_px", "pixels"), ("height_m", "metres"), ("tilt_deg", "degrees"), ("roll_deg", "degrees"))


@dataclass(frozen=True)
class CameraEstimate:
    """A static camera estimated from people (:func:`pedenv.calibration.fit.estimate_camera`).

    focal: pixels. height: metres above the ground. tilt, roll: radians (tilt > 0 looks down).
    covariance: (4, 4) of (focal px, height m, tilt rad, roll rad); a focal length that was
    given (``focal_given``) has zero variance. size: (width, height) pixels. centre: the
    principal point (u, v) pixels. people, observations: distinct people and person-images
    the fit used. rms_px: root mean square of the head points' misfit, pixels. road: where a
    vehicle camera's road cue was combined (:func:`pedenv.calibration.vehicle.combine`), its
    summary (the road's own pitch, the people's tilt, their disagreement in sigmas), else None.
    position: a vehicle camera's (x, y) in the vehicle frame of the ego poses, metres, given
    (``camera_position``), not estimated; the estimate's ground frame lies under the camera.
    """

    focal: float
    height: float
    tilt: float
    roll: float
    covariance: np.ndarray
    size: tuple[int, int]
    centre: tuple[float, float]
    people: int
    observations: int
    rms_px: float
    focal_given: bool = False
    road: dict | None = None
    position: tuple[float, float] = (0.0, 0.0)

    @property
    def std(self) -> np.ndarray:
        """(4,) 1-sigma of (focal px, height m, tilt rad, roll rad)."""
        return np.sqrt(np.maximum(np.diag(self.covariance), 0.0))

    def camera(self, mount: str = "static") -> Camera:
        """The estimate as a :class:`~pedenv.records.Camera` (``mount`` static, or vehicle: the
        vehicle origin on the road :attr:`position` behind and right of the camera (under it by
        default), its x axis the camera's horizontal view)."""
        camera = static_camera(self.focal, self.height, self.tilt, self.roll, self.size, self.centre)
        if mount == "static":
            return camera
        mount_pose = camera.cam_to_vehicle.copy()
        mount_pose[:2, 3] = self.position
        return Camera(camera.intrinsics, camera.width, camera.height, mount_pose, mount)

    def uncertainty(self) -> dict[str, float]:
        """1-sigma of each parameter in the units of :data:`PARAMETERS`."""
        s = self.std
        return {"focal_px": float(s[0]), "height_m": float(s[1]), "tilt_deg": float(np.degrees(s[2])),
                "roll_deg": float(np.degrees(s[3]))}

    def summary(self) -> dict:
        """Parameters, their 1-sigma and what the fit rested on, as JSON-ready numbers."""
        return {"focal_px": self.focal, "fov_deg": float(np.degrees(2 * np.arctan(self.size[0] / (2 * self.focal)))),
                "height_m": self.height, "tilt_deg": float(np.degrees(self.tilt)),
                "roll_deg": float(np.degrees(self.roll)), "std": self.uncertainty(), "people": self.people,
                "observations": self.observations, "rms_px": self.rms_px, "focal_given": self.focal_given,
                **({"road": self.road} if self.road is not None else {}),
                **({"camera_position": list(self.position)} if any(self.position) else {})}
