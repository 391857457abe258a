"""pedenv: a pedestrian environment model from one monocular camera and ego localisation.

    from pedenv import Config, PedestrianEnvironmentModel
    model = PedestrianEnvironmentModel(Config())
    state = model.update(frame)
"""

from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel
from pedenv.pose import create_pose_backend
from pedenv.records import Camera, Detections, EgoPose, Frame, GroundTruth, Scene
from pedenv.state import EnvironmentState, Pedestrians

__version__ = "0.1.0"

__all__ = [
    "Camera", "Config", "Detections", "EgoPose", "EnvironmentState", "Frame", "GroundTruth", "InputError",
    "PedestrianEnvironmentModel", "Pedestrians", "Scene", "create_pose_backend",
]
