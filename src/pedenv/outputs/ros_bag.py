"""``--ros-out FILE.mcap``: the environment model as ROS 2 messages in a rosbag2 MCAP file (rosbags' writer).

Topics (every message stamped with the frame's time; frames in :mod:`pedenv.outputs.ros_messages`):

* ``/pedestrians``: ``vision_msgs/Detection3DArray`` (track id, class ``pedestrian``, position
  with its covariance, a body-sized box), world frame;
* ``/pedestrians/markers``: ``visualization_msgs/MarkerArray`` for RViz;
* ``/pedestrians/tracked_objects``: ``autoware_perception_msgs/TrackedObjects``;
* ``/tf``: ``tf2_msgs/TFMessage``, world -> base_link -> camera_optical.

The file is the MCAP that rosbags' rosbag2 writer makes (``ros2`` profile, message definitions
and QoS stored in it), moved out of its bag folder: Foxglove and ``ros2 bag play FILE.mcap``
open it as it is. Log times are the frame stamps; a scene that starts before the previous
one ended is shifted to one second after it (as the Foxglove MCAP). ``close()`` finishes the
file with every frame written, also when the run stopped at a bad frame.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from pedenv.errors import InputError
from pedenv.outputs.ros_messages import detections, markers, tracked_objects, transforms
from pedenv.outputs.ros_types import ros2_typestore
from pedenv.paths import writable_file
from pedenv.records import Frame
from pedenv.state import EnvironmentState

TOPICS = {"/pedestrians": "vision_msgs/msg/Detection3DArray",
          "/pedestrians/markers": "visualization_msgs/msg/MarkerArray",
          "/pedestrians/tracked_objects": "autoware_perception_msgs/msg/TrackedObjects",
          "/tf": "tf2_msgs/msg/TFMessage"}
_BUILD = {"/pedestrians": detections, "/pedestrians/markers": markers,
          "/pedestrians/tracked_objects": tracked_objects}


class RosBagWriter:
    """A :class:`pedenv.outputs.sinks.FrameSink` writing the topics above to ``path`` (``.mcap``)."""

    def __init__(self, path: str | Path) -> None:
        from rosbags.rosbag2 import StoragePlugin, Writer

        self.path = writable_file(Path(path), "ROS 2 bag")
        if self.path.suffix != ".mcap":
            raise InputError(f"--ros-out {self.path}: the file must end in .mcap (a rosbag2 in MCAP storage)")
        try:  # a fresh folder of its own beside the file: nothing there is replaced or deleted
            self._partial = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.partial-", dir=self.path.parent))
        except OSError as exc:
            raise InputError(f"--ros-out {self.path}: cannot be written: {exc.strerror or exc}") from None
        self._folder = self._partial / "bag"
        self._store = ros2_typestore()
        self._writer: Any = Writer(self._folder, version=9, storage_plugin=StoragePlugin.MCAP)
        self._writer.open()
        self._connections = {topic: self._writer.add_connection(topic, kind, typestore=self._store)
                             for topic, kind in TOPICS.items()}
        self._scene: str | None = None
        self._offset_ns = 0
        self._last_ns = -1

    def write(self, state: EnvironmentState, frame: Frame) -> None:
        ns = int(round(state.timestamp * 1e9))
        if state.scene != self._scene:
            self._scene = state.scene
            self._offset_ns = 0 if ns > self._last_ns else self._last_ns + 1_000_000_000 - ns
        log_ns = ns + self._offset_ns
        if log_ns < 0:
            raise InputError(f"--ros-out {self.path}: frame {state.frame_index} at {state.timestamp} s is before "
                             "1970 (ROS time 0)")
        self._last_ns = log_ns
        messages = {topic: build(self._store, state, log_ns) for topic, build in _BUILD.items()}
        messages["/tf"] = transforms(self._store, state, np.asarray(frame.camera.cam_to_vehicle), log_ns)
        for topic, msg in messages.items():
            self._writer.write(self._connections[topic], log_ns, self._store.serialize_cdr(msg, TOPICS[topic]))

    def close(self) -> None:
        if self._writer is None:
            return
        writer, self._writer = self._writer, None
        writer.close()
        inner = self._folder / f"{self._folder.name}.mcap"
        shutil.move(str(inner), str(self.path))
        shutil.rmtree(self._partial, ignore_errors=True)
