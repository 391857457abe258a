"""The overlay PNGs of ``pedenv run``: lossless either way, small or fast to write.

A PNG's cost is its deflate compression: OpenCV's fastest setting (filter ``Sub``, zlib level 1,
run-length strategy) takes about 40 ms of one core per 1600x900 frame on this project's 2-core
machine, more than a 384x640 pass of the pose network (docs/speed.md). ``png_compression``:

- ``"none"`` (the default of ``pedenv run``): deflate's stored blocks (no compression, written
  here with numpy and zlib, a band of rows at a time): about 5 ms per 1600x900 frame, 4.3 MB per
  overlay (width x height x 3 bytes, plus 0.04 %);
- ``"fast"``: OpenCV's fastest deflate: about 1.5 MB per 1600x900 overlay of a street video.

Both are ordinary 8-bit RGB PNGs that every viewer reads, pixel for pixel the same image.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.paths import writable_file

#: The formats of ``pedenv run``'s overlays (``--overlays``): JPEG (the default, small) or PNG (lossless).
OVERLAY_FORMATS = ("jpeg", "png")
#: JPEG quality of the overlays: a 1600x900 overlay of a real street is about 0.3 MB (docs/outputs.md).
JPEG_QUALITY = 90
#: The valid values of ``png_compression``.
PNG_COMPRESSIONS = ("fast", "none")
_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_BAND_BYTES = 2**18  # rows stored a band at a time: an IDAT chunk each, well below the 8 MB where OpenCV warns


def check_png_compression(name: str, value: object) -> str:
    """``value`` when it is one of :data:`PNG_COMPRESSIONS`, else one InputError naming ``name``."""
    if not isinstance(value, str) or value not in PNG_COMPRESSIONS:
        raise InputError(f"{name} must be one of {', '.join(PNG_COMPRESSIONS)}, got {value!r}")
    return value


def encode_png(image_rgb: np.ndarray, compression: str = "none") -> bytes:
    """The PNG file of ``image_rgb``: (H, W, 3) uint8 RGB; ``compression`` (module doc)."""
    return b"".join(_png_parts(image_rgb, compression))


def write_png(path: str | Path, image_rgb: np.ndarray, compression: str = "none") -> Path:
    """Write ``image_rgb`` ((H, W, 3) uint8 RGB) as the PNG ``path`` (its folder created);
    one InputError when it cannot be written. ``none`` writes the file piece by piece, so no
    copy of the whole image is made (each would cost the 1000 page faults of 4 MB here)."""
    path = writable_file(Path(path), "image")
    _write_parts(path, _png_parts(image_rgb, compression))
    return path


def write_jpeg(path: str | Path, image_rgb: np.ndarray, quality: int = JPEG_QUALITY) -> Path:
    """Write ``image_rgb`` ((H, W, 3) uint8 RGB) as the JPEG ``path`` (its folder created); one
    InputError when it cannot be written (a file cut by a full disk is removed)."""
    path = writable_file(Path(path), "image")
    ok, data = cv2.imencode(".jpg", cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, quality])
    if not ok:
        raise InputError(f"{path}: cannot encode the image as JPEG")
    _write_parts(path, [data.data])
    return path


def _write_parts(path: Path, parts: Iterator[bytes | memoryview] | list[bytes | memoryview]) -> None:
    try:
        with path.open("wb") as f:
            for part in parts:
                f.write(part)
    except OSError as exc:
        path.unlink(missing_ok=True)  # no cut image is left behind
        raise InputError(f"{path}: cannot write the image: {exc.strerror or exc}") from None


def _png_parts(image_rgb: np.ndarray, compression: str) -> Iterator[bytes | memoryview]:
    """The bytes of the PNG file of ``image_rgb`` ((H, W, 3) uint8 RGB), in pieces."""
    check_png_compression("png_compression", compression)
    if image_rgb.ndim != 3 or image_rgb.shape[2] != 3 or image_rgb.dtype != np.uint8:
        raise ValueError(f"image must be (H, W, 3) uint8, got {image_rgb.shape} {image_rgb.dtype}")
    if compression == "fast":
        ok, data = cv2.imencode(".png", cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR))
        if not ok:
            raise InputError("cannot encode the image as PNG")
        yield data.data  # the encoded bytes, not copied
        return
    h, w, _ = image_rgb.shape
    yield _SIGNATURE
    yield from _chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))  # 8-bit RGB, deflate, no interlace
    deflate = zlib.compressobj(0)  # stored blocks
    band = max(1, _BAND_BYTES // (3 * w + 1))
    rows = np.zeros((min(band, h), 3 * w + 1), np.uint8)  # column 0: each row's filter byte, 0 (None)
    for top in range(0, h, band):
        n = min(band, h - top)
        rows[:n, 1:] = image_rgb[top:top + n].reshape(n, 3 * w)
        yield from _chunk(b"IDAT", deflate.compress(rows[:n].data))
    yield from _chunk(b"IDAT", deflate.flush())
    yield from _chunk(b"IEND", b"")


def _chunk(kind: bytes, data: bytes | memoryview) -> list[bytes | memoryview]:
    """One PNG chunk's parts: length, type, data, CRC-32 of type and data (none for empty IDAT data)."""
    if kind == b"IDAT" and not len(data):
        return []
    return [struct.pack(">I", len(data)), kind, data, struct.pack(">I", zlib.crc32(data, zlib.crc32(kind)))]
