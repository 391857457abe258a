"""Scenes held in memory (e.g. freshly generated synthetic scenes) as a Dataset."""

from __future__ import annotations

from collections.abc import Iterator, Sequence

from pedenv.errors import InputError
from pedenv.records import Frame, Scene


class MemoryDataset:
    """A :class:`~pedenv.datasets.Dataset` over a list of :class:`~pedenv.records.Scene`."""

    def __init__(
        self, scenes: Sequence[Scene], name: str = "memory", default_pose_backend: str = "ground-truth"
    ) -> None:
        self._scenes = {s.name: s for s in scenes}
        self.name = name
        self.default_pose_backend = default_pose_backend

    def scene_names(self) -> list[str]:
        return list(self._scenes)

    def frames(self, scene: str) -> Iterator[Frame]:
        if scene not in self._scenes:
            raise InputError(f"unknown scene {scene!r}; scenes here: {', '.join(self._scenes)}")
        return iter(self._scenes[scene].frames)
