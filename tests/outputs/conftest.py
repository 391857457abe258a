"""Two short built-in scenes evaluated once with every per-frame output switched on."""

import warnings

import pytest
from sink_runs import FailingModel, outputs_in, short_scenes

from pedenv.apps.evaluate import run_evaluation
from pedenv.config import Config
from pedenv.datasets.memory import MemoryDataset
from pedenv.errors import InputError


@pytest.fixture(scope="session")
def evaluated(tmp_path_factory):
    """(output folder, EvaluationResult, scenes) of the two short scenes with every output."""
    folder = tmp_path_factory.mktemp("outputs")
    scenes = short_scenes(with_image=True)
    dataset = MemoryDataset(scenes, name="synthetic", default_pose_backend="detector-model")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = run_evaluation(dataset, config=Config(), output_dir=folder, extra_outputs=outputs_in(folder))
    result.extras["warnings"] = [str(w.message) for w in caught]
    return folder, result, scenes


@pytest.fixture(scope="session")
def interrupted(tmp_path_factory):
    """The output folder of the same run stopped by a bad frame at frame 25 of the second scene."""
    folder = tmp_path_factory.mktemp("interrupted")
    dataset = MemoryDataset(short_scenes(), name="synthetic", default_pose_backend="detector-model")
    with pytest.raises(InputError, match="broken on purpose"):
        run_evaluation(dataset, config=Config(), output_dir=folder, extra_outputs=outputs_in(folder),
                       model_factory=FailingModel)
    return folder
