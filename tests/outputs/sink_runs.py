"""Helpers of the output tests: two short built-in scenes, the output set, a model that fails on purpose."""

from dataclasses import replace

import numpy as np

from pedenv.apps.demo import builtin_scenes
from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.records import Scene

FRAMES = 40  # per scene


def short_scenes(with_image: bool = False) -> list[Scene]:
    """red-light-crossing and drive-30kmh-sidewalk, their first 40 frames; the second with a grey image."""
    scenes = [Scene(s.name, s.frames[:FRAMES]) for s in builtin_scenes(0, count=2)]
    if with_image:
        cam = scenes[1].frames[0].camera
        grey = np.full((cam.height, cam.width, 3), 90, np.uint8)
        scenes[1] = Scene(scenes[1].name, tuple(replace(f, image=grey) for f in scenes[1].frames))
    return scenes


def outputs_in(folder) -> ExtraOutputs:
    return ExtraOutputs(parquet=folder / "environment.parquet", matches_parquet=folder / "matches.parquet",
                        rerun=folder / "run.rrd", mcap=folder / "run.mcap", birds_eye_video=folder / "birds_eye.mp4")


class FailingModel(PedestrianEnvironmentModel):
    """The real model, raising InputError at frame ``FAIL_AT`` of the second scene (a bad frame)."""

    FAIL_AT = 25

    def update(self, frame):
        if frame.scene == "drive-30kmh-sidewalk" and frame.index == self.FAIL_AT:
            raise InputError(f"frame {frame.index}: broken on purpose")
        return super().update(frame)
