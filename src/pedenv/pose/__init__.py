"""2D pose backends: a small Protocol and a name registry.

Heavy dependencies (onnxruntime sessions, torch, ultralytics) are imported inside the
backend that needs them, when it is created.
"""

from pedenv.pose.base import POSE_BACKENDS, PoseBackend, create_pose_backend

__all__ = ["POSE_BACKENDS", "PoseBackend", "create_pose_backend"]
