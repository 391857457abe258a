"""The ``synthetic`` dataset adapter over stored scenes."""

from __future__ import annotations

import pytest

from pedenv.datasets import open_dataset
from pedenv.errors import InputError
from pedenv.records import Scene
from pedenv.synthetic import generate_scenes
from pedenv.synthetic.dataset import SyntheticDataset
from pedenv.synthetic.storage import write_scenes

from scene_checks import assert_scenes_equal


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    root = tmp_path_factory.mktemp("synthetic")
    scenes = generate_scenes(2, ["standing-pedestrians", "red-light-crossing"], duration_s=1.5)
    write_scenes(scenes, root)
    return root, scenes


def test_open_by_name_lists_scenes_and_yields_frames(stored):
    root, scenes = stored
    dataset = open_dataset("synthetic", root)
    assert isinstance(dataset, SyntheticDataset)
    assert (dataset.name, dataset.default_pose_backend) == ("synthetic", "detector-model")
    assert dataset.scene_names() == ["red-light-crossing", "standing-pedestrians"]
    for scene in scenes:
        frames = tuple(dataset.frames(scene.name))
        assert_scenes_equal(Scene(scene.name, frames, scene.description), scene)


@pytest.mark.parametrize("layout, message", [("missing", "does not exist"), ("empty", "holds no scenes")])
def test_bad_roots_raise_input_error_naming_the_folder(tmp_path, layout, message):
    root = tmp_path / "data"
    if layout == "empty":
        (root / "not-a-scene").mkdir(parents=True)
    with pytest.raises(InputError, match=message) as info:
        SyntheticDataset(root)
    assert str(root) in str(info.value)


def test_unknown_scene_lists_the_existing_ones(stored):
    with pytest.raises(InputError, match="scenes: red-light-crossing, standing-pedestrians"):
        SyntheticDataset(stored[0]).frames("crowd")
