"""Image files in and out: (H, W, 3) uint8 RGB arrays, one clear error per bad file."""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.outputs.output_dir import writable_file


def read_image_rgb(path) -> np.ndarray:
    """(H, W, 3) uint8 RGB of the image file at ``path``; an unreadable file raises InputError."""
    data = np.fromfile(str(path), dtype=np.uint8) if Path(path).is_file() else None
    if data is None:
        raise InputError(f"{path}: image file not found")
    bgr = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if bgr is None:
        raise InputError(f"{path}: cannot read the image (corrupt or not an image)")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def write_image(path: Path, image_rgb: np.ndarray) -> Path:
    """Write an RGB image (format from the suffix), creating the folder."""
    path = writable_file(path, "image")
    if not cv2.imwrite(str(path), cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR)):
        raise InputError(f"{path}: cannot write the image")
    return path
