"""Datasets: adapters that yield typed :class:`~pedenv.records.Frame` objects, by name.

A dataset converts its own conventions (Unreal's left-handed axes, degrees,
microseconds, quaternions) inside the adapter; the core sees one right-handed world.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Protocol

from pedenv.errors import InputError
from pedenv.records import Frame


class Dataset(Protocol):
    """A set of named scenes on disk."""

    name: str
    #: the pose backend used when the user names none
    default_pose_backend: str

    def scene_names(self) -> list[str]: ...

    # optional: ``default_scenes() -> list[str]``, the scenes run when none are named

    def frames(self, scene: str) -> Iterator[Frame]: ...


#: Dataset name -> "module:class"; each class takes ``(data_root, **options)``.
DATASETS: dict[str, str] = {
    "synthetic": "pedenv.synthetic.dataset:SyntheticDataset",
    "nuscenes": "pedenv.datasets.nuscenes:NuScenesDataset",
    "carla": "pedenv.datasets.carla:CarlaDataset",
    "kitti": "pedenv.datasets.kitti:KittiTrackingDataset",
    "kitti-tracking": "pedenv.datasets.kitti_drives:KittiDrivesDataset",
}

#: Format name of ``pedenv simulate --format`` -> "module:function(scenes, output_dir)".
SCENE_WRITERS: dict[str, str] = {
    "synthetic": "pedenv.synthetic.storage:write_scenes",
    "nuscenes": "pedenv.datasets.nuscenes_export:write_nuscenes",
    "carla": "pedenv.datasets.carla_export:write_carla",
}


def _load(table: dict[str, str], kind: str, name: str) -> Any:
    if name not in table:
        raise InputError(f"unknown {kind} {name!r}; valid: {', '.join(table)}")
    module, attr = table[name].split(":")
    return getattr(importlib.import_module(module), attr)


def open_dataset(name: str, data_root: str | Path, **options: Any) -> Dataset:
    """Open the dataset registered as ``name`` under ``data_root``."""
    return _load(DATASETS, "dataset", name)(Path(data_root), **options)


def scene_writer(name: str) -> Any:
    """The function writing scenes in format ``name``: ``write(scenes, output_dir)``."""
    return _load(SCENE_WRITERS, "scene format", name)
