"""Images and cameras of ROS messages: ``sensor_msgs/Image``, ``CompressedImage`` and ``CameraInfo``.

Every image becomes (H, W, 3) uint8 RGB. A camera with lens distortion gets its images
undistorted (OpenCV) onto the pinhole camera of the same K before the pose network sees them.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.images import encoded_image_size
from pedenv.recordings.bag_source import RosMessage
from pedenv.recordings.calibration_fields import camera_problem

IMAGE_TYPE = "sensor_msgs/msg/Image"
COMPRESSED_TYPE = "sensor_msgs/msg/CompressedImage"
CAMERA_INFO_TYPE = "sensor_msgs/msg/CameraInfo"

#: Raw encodings read, with (channels, bytes per channel). Bayer and YUV are converted by OpenCV.
ENCODINGS = {"rgb8": (3, 1), "bgr8": (3, 1), "rgba8": (4, 1), "bgra8": (4, 1), "mono8": (1, 1), "8UC1": (1, 1),
             "8UC3": (3, 1), "mono16": (1, 2), "16UC1": (1, 2), "bayer_rggb8": (1, 1), "bayer_bggr8": (1, 1),
             "bayer_gbrg8": (1, 1), "bayer_grbg8": (1, 1), "yuv422": (2, 1), "uyvy": (2, 1), "yuv422_yuy2": (2, 1),
             "yuyv": (2, 1)}
_TO_RGB = {"bgr8": cv2.COLOR_BGR2RGB, "8UC3": cv2.COLOR_BGR2RGB, "rgba8": cv2.COLOR_RGBA2RGB,
           "bgra8": cv2.COLOR_BGRA2RGB, "mono8": cv2.COLOR_GRAY2RGB, "8UC1": cv2.COLOR_GRAY2RGB,
           "mono16": cv2.COLOR_GRAY2RGB, "16UC1": cv2.COLOR_GRAY2RGB,
           # ROS names the Bayer pattern by its first row; OpenCV by the second row's pixels 2-3
           "bayer_rggb8": cv2.COLOR_BayerBG2RGB, "bayer_bggr8": cv2.COLOR_BayerRG2RGB,
           "bayer_gbrg8": cv2.COLOR_BayerGR2RGB, "bayer_grbg8": cv2.COLOR_BayerGB2RGB,
           "yuv422": cv2.COLOR_YUV2RGB_UYVY, "uyvy": cv2.COLOR_YUV2RGB_UYVY,
           "yuv422_yuy2": cv2.COLOR_YUV2RGB_YUY2, "yuyv": cv2.COLOR_YUV2RGB_YUY2}
#: The distortion models read, with the number of coefficients ROS defines for each.
DISTORTION_MODELS = {"plumb_bob": 5, "rational_polynomial": 8, "equidistant": 4}
#: Largest distortion coefficient in size: calibrated lenses, fisheyes included, stay below about
#: 10 (OpenCV's rational model's k4..k6 reach a few tens); far beyond it the undistortion maps
#: every pixel off the image (black frames).
MAX_DISTORTION_COEFFICIENT = 100.0
#: Encodings whose two-pixel groups need an even width (YUV 4:2:2 packs U and V per pixel pair).
PAIRED_ENCODINGS = ("yuv422", "uyvy", "yuv422_yuy2", "yuyv")


def image_rgb(msg: RosMessage, msgtype: str, size: tuple[int, int]) -> np.ndarray:
    """(H, W, 3) uint8 RGB of an Image or CompressedImage message whose camera is ``size``
    (width, height) pixels; InputError says what is wrong. The size is checked before decoding
    (a compressed image's from its header, as image files are: :func:`pedenv.images.encoded_image_size`)."""
    if msgtype == COMPRESSED_TYPE:
        fmt = str(msg.format).lower()
        if "compresseddepth" in fmt.replace(" ", ""):
            raise InputError(f"compressed depth images ({msg.format!r}) are not camera images")
        data = np.asarray(msg.data, np.uint8)
        _check_size(encoded_image_size("the compressed image", data.tobytes()), size)
        bgr = cv2.imdecode(np.asarray(msg.data, np.uint8), cv2.IMREAD_COLOR) if len(msg.data) else None
        if bgr is None:
            raise InputError(f"the compressed image (format {msg.format!r}, {len(msg.data)} bytes) cannot be decoded")
        return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
    encoding = str(msg.encoding)
    if encoding not in ENCODINGS:
        raise InputError(f"unknown image encoding {encoding!r} (known: {', '.join(ENCODINGS)})")
    channels, depth = ENCODINGS[encoding]
    h, w, step = int(msg.height), int(msg.width), int(msg.step)
    _check_size((w, h), size)
    if encoding in PAIRED_ENCODINGS and w % 2:
        raise InputError(f"a {encoding} image needs an even width (pixels come in pairs), got {w}")
    data = np.asarray(msg.data, np.uint8)
    if h <= 0 or w <= 0 or step < w * channels * depth or len(data) != h * step:
        raise InputError(f"image fields disagree: {w}x{h} {encoding}, step {step}, {len(data)} data bytes "
                         f"(expected step >= {w * channels * depth} and height * step = {h * step} bytes)")
    rows = data.reshape(h, step)[:, :w * channels * depth]
    if depth == 2:
        dtype = ">u2" if msg.is_bigendian else "<u2"
        pixels = (rows.copy().view(dtype).reshape(h, w) >> 8).astype(np.uint8)  # 16 -> 8 bits, as cv_bridge
    else:
        pixels = np.ascontiguousarray(rows.reshape(h, w, channels) if channels > 1 else rows.reshape(h, w))
    return pixels if encoding == "rgb8" else cv2.cvtColor(pixels, _TO_RGB[encoding])


def _check_size(got: tuple[int, int], size: tuple[int, int]) -> None:
    if got != size:
        raise InputError(f"the image is {got[0]}x{got[1]} pixels, the CameraInfo says {size[0]}x{size[1]}")


@dataclass(frozen=True)
class CameraModel:
    """The camera of a CameraInfo message.

    intrinsics: (3, 3) float, pixels. width, height: pixels. model: the distortion model.
    distortion: (D,) float, the model's coefficients (all zero: no distortion).
    frame_id: the optical frame the images are in.
    """

    intrinsics: np.ndarray
    width: int
    height: int
    model: str
    distortion: np.ndarray
    frame_id: str

    @property
    def distorted(self) -> bool:
        return bool(np.any(self.distortion != 0.0))


def camera_model(msg: RosMessage) -> CameraModel:
    """The :class:`CameraModel` of a CameraInfo message (ROS 1's ``K``, ``D`` or ROS 2's ``k``, ``d``)."""
    k = np.asarray(getattr(msg, "k", None) if hasattr(msg, "k") else msg.K, np.float64).reshape(3, 3)
    d = np.asarray(getattr(msg, "d", None) if hasattr(msg, "d") else msg.D, np.float64).ravel()
    model = str(msg.distortion_model) or ("plumb_bob" if not np.any(d) else "")
    if not np.all(np.isfinite(k)) or k[0, 0] <= 0 or k[1, 1] <= 0 or not np.array_equal(k[2], [0.0, 0.0, 1.0]):
        raise InputError(f"K is not a camera matrix: {k.tolist()} (all zero: an uncalibrated camera)")
    if not np.all(np.isfinite(d)):
        raise InputError(f"the distortion coefficients are not finite: {d.tolist()}")
    if np.any(d) and model not in DISTORTION_MODELS:
        raise InputError(f"unknown distortion model {model!r} (known: {', '.join(DISTORTION_MODELS)})")
    if np.any(d) and len(d) != DISTORTION_MODELS[model]:
        raise InputError(f"the {model} model takes {DISTORTION_MODELS[model]} coefficients (field d), got {len(d)}")
    if np.any(np.abs(d) > MAX_DISTORTION_COEFFICIENT):
        i = int(np.argmax(np.abs(d)))
        raise InputError(f"distortion coefficient d[{i}] = {d[i]:g} is beyond {MAX_DISTORTION_COEFFICIENT:g} in size "
                         "(pedenv.recordings.bag_images.MAX_DISTORTION_COEFFICIENT)")
    width, height = int(msg.width), int(msg.height)
    problem = camera_problem(k, width, height)
    if problem is not None:
        raise InputError(f"CameraInfo {problem}")
    return CameraModel(k, width, height, model, d, str(msg.header.frame_id))


class Undistorter:
    """Remaps distorted images onto the pinhole camera with the same K (OpenCV, bilinear)."""

    def __init__(self, camera: CameraModel) -> None:
        size, k = (camera.width, camera.height), camera.intrinsics
        if camera.model == "equidistant":
            self.maps = cv2.fisheye.initUndistortRectifyMap(k, camera.distortion, np.eye(3), k, size, cv2.CV_16SC2)
        else:
            self.maps = cv2.initUndistortRectifyMap(k, camera.distortion, None, k, size, cv2.CV_16SC2)

    def __call__(self, image: np.ndarray) -> np.ndarray:
        """(H, W, 3) uint8 distorted -> (H, W, 3) uint8 undistorted."""
        return cv2.remap(image, self.maps[0], self.maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
