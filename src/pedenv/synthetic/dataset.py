"""The ``synthetic`` dataset: scenes written by :func:`pedenv.synthetic.storage.write_scenes`."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

from pedenv.errors import InputError
from pedenv.records import Frame
from pedenv.synthetic.storage import read_scene


class SyntheticDataset:
    """Scenes stored as ``<data_root>/<scene name>/{scene.json, frames.npz}``.

    The frames carry ground truth but no detections; the default pose backend
    ``detector-model`` simulates a pose network from that ground truth.
    """

    name = "synthetic"
    default_pose_backend = "detector-model"

    def __init__(self, data_root: str | Path) -> None:
        root = Path(data_root)
        if not root.is_dir():
            raise InputError(f"synthetic data folder {root} does not exist (write one with `pedenv simulate`)")
        self._folders = {p.name: p for p in sorted(root.iterdir()) if (p / "scene.json").is_file()}
        if not self._folders:
            raise InputError(f"synthetic data folder {root} holds no scenes (no <scene>/scene.json)")
        self.data_root = root

    def scene_names(self) -> list[str]:
        """Names of the stored scenes, sorted."""
        return list(self._folders)

    def frames(self, scene: str) -> Iterator[Frame]:
        """The frames of ``scene`` in time order; InputError listing the scenes for an unknown name."""
        if scene not in self._folders:
            raise InputError(f"no scene {scene!r} in {self.data_root}; scenes: {', '.join(self._folders)}")
        return iter(read_scene(self._folders[scene]).frames)
