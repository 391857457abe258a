"""An estimated camera as a calibration YAML in the input format (``mount: static``), marked estimated."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from pedenv.calibration.estimate import CameraEstimate

#: The note written into every estimated calibration file.
ESTIMATED_NOTE = ("estimated by pedenv from the people it saw (pedenv calibrate); check calibration.png before "
                  "reusing it")


def calibration_mapping(estimate: CameraEstimate, mount: str = "static") -> dict:
    """The calibration file's fields: size, intrinsics, the static mounting, ``estimated: true``
    and the 1-sigma ``uncertainty`` of focal length (px), height (m), tilt and roll (deg)."""
    camera = estimate.camera(mount)
    rotation = camera.cam_to_vehicle[:3, :3]
    return {
        "width": camera.width, "height": camera.height,
        "intrinsics": np.round(camera.intrinsics, 3).tolist(),
        "cam_to_vehicle": {"rotation": np.round(rotation, 6).tolist(),
                           "translation": np.round(camera.cam_to_vehicle[:3, 3], 4).tolist()},
        "mount": mount,
        "estimated": True,
        "uncertainty": {k: round(v, 4) for k, v in estimate.uncertainty().items()},
    }


def write_calibration(path: str | Path, estimate: CameraEstimate, mount: str = "static") -> Path:
    """Write ``estimate`` as a calibration YAML at ``path`` (readable by ``--calibration``)."""
    path = Path(path)
    text = f"# {ESTIMATED_NOTE}\n" + yaml.safe_dump(calibration_mapping(estimate, mount), sort_keys=False,
                                                      default_flow_style=None)
    path.write_text(text, encoding="utf-8")
    return path
