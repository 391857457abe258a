"""Image files in and out: (H, W, 3) uint8 RGB arrays, one clear error per bad file.

An image's size is read from its header before it is decoded: a file of a few hundred
kilobytes can announce 30000x30000 pixels (2.7 GB once decoded), so images above
:data:`MAX_IMAGE_PIXELS` (or files above :data:`MAX_IMAGE_FILE_BYTES`) are refused with one
:class:`~pedenv.errors.InputError` naming the file. Files are read and written by Python and
coded in memory by OpenCV, so any file name works (OpenCV's own file calls crash on a name
that is not UTF-8: :mod:`pedenv.paths`).
"""

from __future__ import annotations

import io
import re
import warnings
from pathlib import Path
from typing import BinaryIO

import cv2
import numpy as np
from PIL import Image, UnidentifiedImageError

from pedenv.errors import InputError
from pedenv.paths import check_path, writable_file

#: Most pixels (width x height) of an image pedenv reads: 64 megapixels, about 4 times an
#: 8K frame (7680x4320 is 33 MP); one such image takes 200 MB decoded (RGB, 8 bits).
MAX_IMAGE_PIXELS = 64_000_000
#: Largest image file pedenv reads (bytes): an uncompressed 64 MP RGB image is 192 MB.
MAX_IMAGE_FILE_BYTES = 256 * 2**20


def image_size(path: str | Path) -> tuple[int, int]:
    """(width, height) pixels of the image file at ``path`` from its header, without decoding it.

    Raises InputError for a missing, unreadable or oversized file (see the module doc).
    """
    path = check_path(path, "image")
    try:
        with path.open("rb") as f:  # Pillow reads the header only
            return _checked_size(path, f)
    except FileNotFoundError:
        raise InputError(f"{path}: image file not found") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the image: {exc.strerror or exc}") from None


def read_image_rgb(path: str | Path) -> np.ndarray:
    """(H, W, 3) uint8 RGB of the image file at ``path``; an unreadable or oversized file raises InputError."""
    data = _read_bytes(path)
    _checked_size(path, io.BytesIO(data))
    bgr = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR) if data else None
    if bgr is None:
        raise InputError(f"{path}: cannot read the image (corrupt or not an image)")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)


def write_image(path: Path, image_rgb: np.ndarray) -> Path:
    """Write an RGB image (format from the suffix, e.g. ``.png``), creating the folder."""
    path = writable_file(path, "image")
    ok, data = cv2.imencode(path.suffix or ".png", cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR))
    if not ok:
        raise InputError(f"{path}: cannot encode the image as {path.suffix or '.png'}")
    try:
        path.write_bytes(data.tobytes())
    except OSError as exc:
        raise InputError(f"{path}: cannot write the image: {exc.strerror or exc}") from None
    return path


def _read_bytes(path: str | Path) -> bytes:
    path = check_path(path, "image")
    try:
        if not path.is_file():
            raise InputError(f"{path}: image file not found")
        size = path.stat().st_size
        if size > MAX_IMAGE_FILE_BYTES:
            raise InputError(f"{path}: the image file is {size / 2**20:.0f} MB, above the limit of "
                             f"{MAX_IMAGE_FILE_BYTES / 2**20:.0f} MB (pedenv.images.MAX_IMAGE_FILE_BYTES)")
        return path.read_bytes()
    except OSError as exc:
        raise InputError(f"{path}: cannot read the image: {exc.strerror or exc}") from None


def _checked_size(path: str | Path, data: BinaryIO) -> tuple[int, int]:
    """(width, height) from the header of ``data`` (a file object; Pillow reads the header only);
    InputError above MAX_IMAGE_PIXELS."""
    try:
        with warnings.catch_warnings():  # Pillow warns above its own limit; ours is lower and an error
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(data) as image:
                width, height = image.size
    except Image.DecompressionBombError as exc:  # above twice Pillow's limit, which is above ours
        pixels = re.search(r"\((\d+) pixels\)", str(exc))
        raise InputError(f"{path}: the image has {pixels.group(1) if pixels else 'more'} pixels, above the limit "
                         f"of {MAX_IMAGE_PIXELS / 1e6:g} megapixels (pedenv.images.MAX_IMAGE_PIXELS)") from None
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError, ImportError):
        # ImportError: ultralytics wraps Image.open and tries pi_heif on a file Pillow cannot identify
        raise InputError(f"{path}: cannot read the image (corrupt or not an image)") from None
    if width * height > MAX_IMAGE_PIXELS:
        raise InputError(f"{path}: the image is {width}x{height} pixels, above the limit of "
                         f"{MAX_IMAGE_PIXELS / 1e6:g} megapixels (pedenv.images.MAX_IMAGE_PIXELS)")
    return width, height


def encoded_image_size(name: str, data: bytes) -> tuple[int, int]:
    """(width, height) pixels of an encoded image held in memory (PNG, JPEG, ...) from its header,
    without decoding it; InputError naming ``name`` when it is unreadable or above :data:`MAX_IMAGE_PIXELS`."""
    return _checked_size(name, io.BytesIO(data))
