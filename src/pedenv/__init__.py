"""pedenv: a pedestrian environment model from one monocular camera and ego localisation.

    from pedenv import Config, Pipeline
    pipeline = Pipeline(Config())        # predict the tracks, detect with them, update the model
    state = pipeline.step(frame)

Layers, each importing only those below it: the core (``records``, ``config``, ``model``,
``tracking``, ``localization``, ``kalman``), the pose network (``pose``), the detection stage
(``detection``: how the network is spent), the per-frame :class:`Pipeline`, and ``apps``/``cli``.
"""

from pedenv.config import Config
from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel
from pedenv.pipeline import Pipeline
from pedenv.recordings.footage import load_recording
from pedenv.records import Camera, Detections, EgoPose, Frame, GroundTruth, PredictedTracks, Scene
from pedenv.state import EnvironmentState, Pedestrians

__version__ = "0.1.0"

__all__ = [
    "Camera", "Config", "Detections", "EgoPose", "EnvironmentState", "Frame", "GroundTruth", "InputError",
    "PedestrianEnvironmentModel", "Pedestrians", "Pipeline", "PredictedTracks", "Scene", "create_detector",
    "load_recording",
]
