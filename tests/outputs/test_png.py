"""The overlay PNGs: ``none`` (stored blocks, written here) and ``fast`` (OpenCV) give back the
same pixels in OpenCV and Pillow; the stored file's size is the raw image's plus its framing."""

from __future__ import annotations

import io

import cv2
import numpy as np
import pytest
from PIL import Image

from pedenv.errors import InputError
from pedenv.outputs.png import encode_png, write_png


@pytest.mark.parametrize("compression", ["none", "fast"])
@pytest.mark.parametrize("shape", [(1, 1, 3), (37, 53, 3), (900, 1600, 3), (1500, 1000, 3)])
def test_both_compressions_give_back_every_pixel(compression, shape):
    image = np.random.default_rng(7).integers(0, 256, shape, dtype=np.uint8)
    data = encode_png(image, compression)
    opencv = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)[..., ::-1]
    pillow = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))
    np.testing.assert_array_equal(opencv, image)
    np.testing.assert_array_equal(pillow, image)


def test_stored_png_is_the_raw_image_plus_its_framing():
    h, w = 900, 1600
    data = encode_png(np.zeros((h, w, 3), np.uint8), "none")
    rows = h * (3 * w + 1)  # a filter byte per row
    framing = 8 + 25 + 12 + 6  # signature, IHDR, IEND, zlib's header and check
    bands = -(-h // (2**18 // (3 * w + 1)))  # an IDAT chunk (12 bytes) per band of rows, and deflate's stored blocks
    assert rows + framing + 12 * bands + 5 * (rows // 65535) <= len(data) <= rows + framing + 12 * (bands + 1) + 5 * (
        rows // 16384 + 2)
    assert 1.0 < len(data) / (h * w * 3) < 1.0005  # 4.3 MB for a 1600x900 overlay
    assert len(encode_png(np.zeros((h, w, 3), np.uint8), "fast")) < 50_000  # deflate: a flat image is small


def test_write_png_creates_the_folder_and_refuses_bad_settings(tmp_path):
    image = np.full((4, 6, 3), 200, np.uint8)
    path = write_png(tmp_path / "overlays" / "000000.png", image, "none")
    np.testing.assert_array_equal(cv2.imread(str(path))[..., ::-1], image)
    with pytest.raises(InputError, match=r"png_compression must be one of fast, none, got 'zip'"):
        encode_png(image, "zip")
    with pytest.raises(ValueError, match=r"image must be \(H, W, 3\) uint8, got \(4, 6\) uint8"):
        encode_png(image[..., 0], "none")


def test_output_options_check_png_compression():
    from pedenv.apps.options import OutputOptions

    assert OutputOptions("out").png_compression == "none"
    with pytest.raises(InputError, match=r"output\.png_compression must be one of fast, none, got 9"):
        OutputOptions("out", png_compression=9)  # type: ignore[arg-type]
