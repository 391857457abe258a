"""Video files through OpenCV under any file name (:func:`pedenv.paths.opencv_path`).

Frames are (H, W, 3) uint8 BGR, as OpenCV has them.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import cv2
import numpy as np

from pedenv.errors import InputError
from pedenv.paths import check_path, opencv_path

#: Frame rates an mp4 is written at (Hz): OpenCV's mp4v encoder refuses below 0.5 and above 65535,
#: and players stall above about 1000; a recording's rate outside (frames 10 µs apart) is clamped.
VIDEO_FPS_RANGE = (1.0, 1000.0)


class VideoOut:
    """An mp4 (``mp4v``) being written: ``write(bgr)`` per frame, ``release()`` at the end.

    path: the file. fps: frames per second, clamped to :data:`VIDEO_FPS_RANGE` (10 when not finite).
    size: (width, height) pixels of every frame.
    ``what`` names the video in the InputError raised when it cannot be opened.
    """

    def __init__(self, path: str | Path, fps: float, size: tuple[int, int], what: str = "video") -> None:
        self.path = check_path(path, what)
        self._names = ExitStack()
        name = self._names.enter_context(opencv_path(self.path))
        rate = min(max(float(fps), VIDEO_FPS_RANGE[0]), VIDEO_FPS_RANGE[1]) if math.isfinite(fps) else 10.0
        self._writer = cv2.VideoWriter(name, cv2.VideoWriter.fourcc(*"mp4v"), rate, size)
        if not self._writer.isOpened():
            self.release()
            raise InputError(f"{self.path}: cannot write the {what}")

    def write(self, bgr: np.ndarray) -> None:
        """Append one frame: (height, width, 3) uint8 BGR."""
        self._writer.write(bgr)

    def release(self) -> None:
        """Finish the file (idempotent)."""
        self._writer.release()
        self._names.close()


@contextmanager
def video_capture(path: str | Path) -> Iterator[cv2.VideoCapture]:
    """An opened ``cv2.VideoCapture`` of ``path`` for the ``with`` block; InputError if it cannot be opened."""
    path = check_path(path, "video")
    with opencv_path(path) as name:
        cap = cv2.VideoCapture(name)
        try:
            if not cap.isOpened():
                raise InputError(f"{path}: cannot open the video")
            yield cap
        finally:
            cap.release()
