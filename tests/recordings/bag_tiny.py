"""A tiny synthetic bag built in a test: grey images, one CameraInfo, a static mount and a /tf or /odom ego.

Each message can be changed before it is written (``change(topic, index, msg)``), so a hostile
bag is the tiny bag with one field set wrong. ``compression``: None, ``"chunks"`` (zstd MCAP
chunks), ``"file"`` or ``"message"`` (rosbag2 zstd compression modes).
"""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np

IMAGE_TOPIC, INFO_TOPIC = "/camera/image_raw", "/camera/camera_info"
WIDTH, HEIGHT = 64, 48
K = [[60.0, 0.0, 32.0], [0.0, 60.0, 24.0], [0.0, 0.0, 1.0]]
#: The camera on base_link: 1.5 m up, looking along x (optical z forward, x right, y down).
MOUNT_XYZ = (1.0, 0.0, 1.5)
MOUNT_WXYZ = (0.5, -0.5, 0.5, -0.5)


def _store():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def _header(t, ns: int, frame: str):
    return t["std_msgs/msg/Header"](stamp=t["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
                                    frame_id=frame)


def _transform(t, ns: int, parent: str, child: str, xyz, wxyz):
    tf = t["geometry_msgs/msg/Transform"](translation=t["geometry_msgs/msg/Vector3"](x=xyz[0], y=xyz[1], z=xyz[2]),
                                          rotation=t["geometry_msgs/msg/Quaternion"](w=wxyz[0], x=wxyz[1], y=wxyz[2],
                                                                                     z=wxyz[3]))
    stamped = t["geometry_msgs/msg/TransformStamped"](header=_header(t, ns, parent), child_frame_id=child,
                                                      transform=tf)
    return t["tf2_msgs/msg/TFMessage"](transforms=[stamped])


def _odometry(t, ns: int, xyz):
    v0 = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    pose = t["geometry_msgs/msg/Pose"](position=t["geometry_msgs/msg/Point"](x=xyz[0], y=xyz[1], z=xyz[2]),
                                       orientation=t["geometry_msgs/msg/Quaternion"](w=1.0, x=0.0, y=0.0, z=0.0))
    return t["nav_msgs/msg/Odometry"](
        header=_header(t, ns, "odom"), child_frame_id="base_link",
        pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)),
        twist=t["geometry_msgs/msg/TwistWithCovariance"](twist=t["geometry_msgs/msg/Twist"](linear=v0, angular=v0),
                                                         covariance=np.zeros(36)))


def camera_info(t, ns: int, width: int = WIDTH, height: int = HEIGHT, model: str = "plumb_bob",
                d=(0.0,) * 5, k=K):
    p = np.zeros((3, 4))
    p[:, :3] = k
    roi = t["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    return t["sensor_msgs/msg/CameraInfo"](header=_header(t, ns, "camera_optical"), height=height, width=width,
                                           distortion_model=model, d=np.array(d, float),
                                           k=np.asarray(k, float).ravel(), r=np.eye(3).ravel(), p=p.ravel(),
                                           binning_x=0, binning_y=0, roi=roi)


def image(t, ns: int, width: int = WIDTH, height: int = HEIGHT, encoding: str = "rgb8"):
    if encoding == "compressed":
        data = cv2.imencode(".png", np.full((height, width, 3), 128, np.uint8))[1].ravel()
        return t["sensor_msgs/msg/CompressedImage"](header=_header(t, ns, "camera_optical"), format="png", data=data)
    channels = 2 if encoding in ("yuyv", "uyvy", "yuv422") else 3
    data = np.full(height * width * channels, 128, np.uint8)
    return t["sensor_msgs/msg/Image"](header=_header(t, ns, "camera_optical"), height=height, width=width,
                                      encoding=encoding, is_bigendian=0, step=width * channels, data=data)


def tiny_bag(out: Path, *, storage: str = "sqlite3", images: int = 3, encoding: str = "rgb8", ego: str = "tf",
             compression: str | None = None, change=lambda topic, index, msg: msg) -> Path:  # noqa: ARG005
    """Write the tiny bag at ``out`` (a rosbag2 folder, or one ``.mcap`` file for ``storage="mcap-file"``):
    ``images`` frames at 10 Hz, the ego driving 1 m/s along x, sampled at 20 Hz."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.rosbag2.enums import CompressionFormat, CompressionMode

    store = _store()
    t = store.types
    records = [("/tf_static", "tf2_msgs/msg/TFMessage", 0, _transform(t, 0, "base_link", "camera_optical", MOUNT_XYZ,
                                                                       MOUNT_WXYZ)),
               (INFO_TOPIC, "sensor_msgs/msg/CameraInfo", 0, camera_info(t, 0))]
    for i in range(2 * images + 1):
        ns = i * 50_000_000
        records.append(("/tf", "tf2_msgs/msg/TFMessage", ns, _transform(t, ns, "odom", "base_link", (i / 20, 0, 0),
                                                                          (1, 0, 0, 0)))
                       if ego == "tf" else ("/odom", "nav_msgs/msg/Odometry", ns, _odometry(t, ns, (i / 20, 0, 0))))
    kind = "sensor_msgs/msg/CompressedImage" if encoding == "compressed" else "sensor_msgs/msg/Image"
    for i in range(images):
        ns = i * 100_000_000 + 1
        records.append((IMAGE_TOPIC, kind, ns, image(t, ns, encoding=encoding)))
    records.sort(key=lambda r: r[2])
    folder = out.with_name(out.stem + "-rosbag2") if storage == "mcap-file" else out
    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    writer = Writer(folder, version=9, storage_plugin=plugin)
    if compression is not None:
        mode = {"chunks": CompressionMode.STORAGE, "file": CompressionMode.FILE, "message": CompressionMode.MESSAGE}
        writer.set_compression(mode[compression], CompressionFormat.ZSTD)
    counts: dict[str, int] = {}
    conns: dict[str, object] = {}
    with writer:
        for topic, _, ns, msg in records:
            index = counts[topic] = counts.get(topic, -1) + 1
            msg = change(topic, index, msg)
            if msg is None:
                continue
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msg.__msgtype__, typestore=store)
            writer.write(conns[topic], ns, store.serialize_cdr(msg, msg.__msgtype__))
    if storage == "mcap-file":
        shutil.move(next(folder.glob("*.mcap")), out)
        shutil.rmtree(folder)
    return out
