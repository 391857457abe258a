"""The built-in synthetic scenes: seeded street scenarios like the paper's CARLA set.

``generate_scenes`` returns :class:`~pedenv.records.Scene` objects whose frames carry
the ego pose, the camera and the ground truth of the visible pedestrians (positions,
boxes, exact COCO-17 skeletons in 2D and 3D). ``DetectorModel`` (the pose backend
``detector-model``) turns that ground truth into noisy detections like a pose network;
``write_scenes`` / ``read_scene`` store scenes on disk and ``SyntheticDataset`` reads
them back as a dataset.
"""

from pedenv.synthetic.generator import generate_scenes
from pedenv.synthetic.scenarios import SCENARIOS

__all__ = ["SCENARIOS", "generate_scenes"]
