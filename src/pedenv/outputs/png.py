"""The overlay PNGs of ``pedenv run``: lossless either way, small or fast to write.

A PNG's cost is its deflate compression: OpenCV's fastest setting (filter ``Sub``, zlib level 1,
run-length strategy) takes about 40 ms of one core per 1600x900 frame on this project's 2-core
machine, more than a 384x640 pass of the pose network (docs/speed.md). ``png_compression``:

- ``"fast"``: OpenCV's fastest deflate: about 1.3-1.5 MB per 1600x900 overlay;
- ``"none"``: deflate's stored blocks (no compression, written here with numpy and zlib):
  about 4 ms per 1600x900 frame, 4.3 MB per overlay (width x height x 3 bytes, plus 0.03 %).

Both are ordinary 8-bit RGB PNGs that every viewer reads, pixel for pixel the same image.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.outputs.output_dir import writable_file

#: The valid values of ``png_compression``.
PNG_COMPRESSIONS = ("fast", "none")
_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_IDAT_BYTES = 2**20  # the stored pixels in chunks of 1 MiB (OpenCV warns above 8 MB a chunk)


def check_png_compression(name: str, value: object) -> str:
    """``value`` when it is one of :data:`PNG_COMPRESSIONS`, else one InputError naming ``name``."""
    if not isinstance(value, str) or value not in PNG_COMPRESSIONS:
        raise InputError(f"{name} must be one of {', '.join(PNG_COMPRESSIONS)}, got {value!r}")
    return value


def encode_png(image_rgb: np.ndarray, compression: str = "fast") -> bytes:
    """The PNG file of ``image_rgb``: (H, W, 3) uint8 RGB; ``compression`` (module doc)."""
    check_png_compression("png_compression", compression)
    if image_rgb.ndim != 3 or image_rgb.shape[2] != 3 or image_rgb.dtype != np.uint8:
        raise ValueError(f"image must be (H, W, 3) uint8, got {image_rgb.shape} {image_rgb.dtype}")
    if compression == "fast":
        ok, data = cv2.imencode(".png", cv2.cvtColor(image_rgb, cv2.COLOR_RGB2BGR))
        if not ok:
            raise InputError("cannot encode the image as PNG")
        return data.tobytes()
    return _stored_png(image_rgb)


def write_png(path: str | Path, image_rgb: np.ndarray, compression: str = "fast") -> Path:
    """Write ``image_rgb`` ((H, W, 3) uint8 RGB) as the PNG ``path`` (its folder created);
    one InputError when it cannot be written."""
    path = writable_file(Path(path), "image")
    data = encode_png(image_rgb, compression)
    try:
        path.write_bytes(data)
    except OSError as exc:
        raise InputError(f"{path}: cannot write the image: {exc.strerror or exc}") from None
    return path


def _stored_png(image_rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of ``image_rgb`` ((H, W, 3) uint8) with filter ``None`` on every row and
    its pixels in deflate's stored blocks (zlib level 0)."""
    h, w, _ = image_rgb.shape
    rows = np.empty((h, 1 + 3 * w), np.uint8)
    rows[:, 0] = 0  # each row's filter byte: None
    rows[:, 1:] = image_rgb.reshape(h, 3 * w)
    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)  # 8 bits, RGB, deflate, adaptive filters, no interlace
    pixels = memoryview(zlib.compress(rows.data, 0))
    parts = [_SIGNATURE, *_chunk(b"IHDR", header)]
    for start in range(0, len(pixels), _IDAT_BYTES):
        parts += _chunk(b"IDAT", pixels[start:start + _IDAT_BYTES])
    return b"".join(parts + _chunk(b"IEND", b""))


def _chunk(kind: bytes, data: bytes | memoryview) -> list[bytes | memoryview]:
    """One PNG chunk's parts: length, type, data, CRC-32 of type and data."""
    return [struct.pack(">I", len(data)), kind, data, struct.pack(">I", zlib.crc32(data, zlib.crc32(kind)))]
