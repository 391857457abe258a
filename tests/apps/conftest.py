"""The one local Ray of a test session (tests marked ``ray``), and small scenes to spread over it."""

import os
import sys
from pathlib import Path

import pytest

from pedenv.datasets.memory import MemoryDataset
from pedenv.synthetic import SCENARIOS, generate_scenes

#: Ray's object store for the tests: small, the test scenes are a few MB.
OBJECT_STORE_BYTES = 200 * 1024**2


@pytest.fixture(scope="session")
def ray_session():
    """A local Ray with 2 CPUs for the whole session, shut down at its end; RayExecutor uses it as it is."""
    import ray  # the ray extra: make test installs it, and CI runs these tests
    # the workers import the test modules' tasks by name, so they get the test folders on their path
    here = Path(__file__).parent
    path = os.pathsep.join([str(here), *(p for p in sys.path if p)])
    ray.init(num_cpus=2, include_dashboard=False, object_store_memory=OBJECT_STORE_BYTES, log_to_driver=False,
             runtime_env={"env_vars": {"PYTHONPATH": path}})
    yield ray
    ray.shutdown()


@pytest.fixture(scope="session")
def short_scenes():
    """Three built-in scenarios of 3 s each (30 frames at 10 Hz), seed 0."""
    return generate_scenes(0, list(SCENARIOS[:3]), duration_s=3.0)


@pytest.fixture
def short_dataset(short_scenes):
    return MemoryDataset(short_scenes, name="synthetic", default_pose_backend="detector-model")
