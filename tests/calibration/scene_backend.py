"""A pose backend over a built-in scene's frames, shared by the calibration tests."""

from __future__ import annotations

from pedenv.records import Frame


class SceneBackend:
    """A pose backend answering each frame (by index) with the detector model on the scene's frame."""

    name = "detector-model"

    def __init__(self, frames: tuple[Frame, ...]) -> None:
        from pedenv.synthetic.detector import DetectorModel

        self.frames, self.model = frames, DetectorModel(0)

    def __call__(self, frame: Frame, tracks=None):
        return self.model(self.frames[frame.index], tracks)
