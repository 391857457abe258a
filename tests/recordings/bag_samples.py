"""Write a ``pedenv run`` recording (calibration YAML, ego poses CSV, images) as a real ROS bag.

With ``rosbags``' own writers: rosbag2 in MCAP or sqlite3 storage, a single ``.mcap`` file
(the MCAP inside a rosbag2 folder) or ROS 1 ``.bag``. The camera goes to ``CameraInfo`` and
``/tf_static`` (base_link -> camera, the YAML's rotation as a quaternion, written back into the
YAML so both forms hold the same numbers), the ego poses to ``/tf`` (odom -> base_link) or
``/odom``, each image to ``Image`` (raw) or ``CompressedImage`` (the image file's own bytes).
"""

from __future__ import annotations

import csv
import shutil
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import yaml

from pedenv.geometry import rotation_to_quaternion
from pedenv.recordings.footage_writer import write_kitti_recording


@dataclass(frozen=True)
class BagForm:
    """storage: mcap, sqlite3, mcap-file or ros1. images: rgb8, bgr8, mono8, bgra8, mono16 or
    compressed. ego: tf or odometry. distortion: (model, coefficients) applied to the images."""

    storage: str = "mcap"
    images: str = "rgb8"
    ego: str = "tf"
    distortion: tuple[str, tuple[float, ...]] | None = None
    camera_frame: str = "camera_optical"
    drop_camera_link: bool = False
    encoding_at: tuple[int, str] | None = None  # (image index, encoding it claims): a bad message on purpose


def quaternion_calibration(recording: Path) -> np.ndarray:
    """Rewrite the recording's YAML rotation as a quaternion ``[w, x, y, z]`` (returned)."""
    path = recording / "calibration.yaml"
    data = yaml.safe_load(path.read_text())
    q = rotation_to_quaternion(np.array(data["cam_to_vehicle"]["rotation"]))
    data["cam_to_vehicle"]["rotation"] = [float(v) for v in q]
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return np.array(data["cam_to_vehicle"]["rotation"])


def kitti_recording(folder: Path, real_samples: Path) -> Path:
    """KITTI tracking 0016 of the real samples written as a recording in ``folder``, its
    calibration's rotation as a quaternion (as bags carry it)."""
    rec = write_kitti_recording(real_samples / "kitti" / "tracking_mini" / "training", "0016", folder)
    quaternion_calibration(rec)
    return rec


def _poses(recording: Path) -> list[tuple[int, list[float], list[float]]]:
    rows = list(csv.reader((recording / "ego_poses.csv").open()))[1:]
    return [(_ns(r[0]), [float(v) for v in r[1:4]], [float(v) for v in r[4:8]]) for r in rows]


def _ns(text: str) -> int:
    whole, _, frac = text.partition(".")
    return int(whole) * 1_000_000_000 + int((frac + "000000000")[:9])


def _images(recording: Path) -> list[tuple[Path, int]]:
    rows = list(csv.reader((recording / "images" / "timestamps.csv").open()))[1:]
    return [(recording / "images" / name, _ns(stamp)) for name, stamp in rows]


class _Messages:
    """Message objects of one ROS version's typestore, field names as that version spells them."""

    def __init__(self, store, ros1: bool) -> None:
        self.store, self.ros1 = store, ros1

    def t(self, name: str):
        return self.store.types[name]

    def header(self, ns: int, frame: str):
        time = self.t("builtin_interfaces/msg/Time")(sec=ns // 10**9, nanosec=ns % 10**9)
        extra = {"seq": 0} if self.ros1 else {}
        return self.t("std_msgs/msg/Header")(stamp=time, frame_id=frame, **extra)

    def transform(self, ns: int, parent: str, child: str, xyz, wxyz):
        v = self.t("geometry_msgs/msg/Vector3")(x=xyz[0], y=xyz[1], z=xyz[2])
        q = self.t("geometry_msgs/msg/Quaternion")(w=wxyz[0], x=wxyz[1], y=wxyz[2], z=wxyz[3])
        tf = self.t("geometry_msgs/msg/Transform")(translation=v, rotation=q)
        return self.t("geometry_msgs/msg/TransformStamped")(header=self.header(ns, parent), child_frame_id=child,
                                                            transform=tf)

    def tf(self, transforms):
        return self.t("tf2_msgs/msg/TFMessage")(transforms=transforms)

    def odometry(self, ns: int, xyz, wxyz):
        p = self.t("geometry_msgs/msg/Point")(x=xyz[0], y=xyz[1], z=xyz[2])
        q = self.t("geometry_msgs/msg/Quaternion")(w=wxyz[0], x=wxyz[1], y=wxyz[2], z=wxyz[3])
        pose = self.t("geometry_msgs/msg/PoseWithCovariance")(pose=self.t("geometry_msgs/msg/Pose")(
            position=p, orientation=q), covariance=np.zeros(36))
        zero = self.t("geometry_msgs/msg/Vector3")(x=0.0, y=0.0, z=0.0)
        twist = self.t("geometry_msgs/msg/TwistWithCovariance")(twist=self.t("geometry_msgs/msg/Twist")(
            linear=zero, angular=zero), covariance=np.zeros(36))
        return self.t("nav_msgs/msg/Odometry")(header=self.header(ns, "odom"), child_frame_id="base_link", pose=pose,
                                               twist=twist)

    def camera_info(self, ns: int, frame: str, k, width: int, height: int, model: str, d):
        p = np.zeros((3, 4))
        p[:, :3] = k
        roi = self.t("sensor_msgs/msg/RegionOfInterest")(x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
        names = ("D", "K", "R", "P") if self.ros1 else ("d", "k", "r", "p")
        mats = dict(zip(names, (np.array(d, float), np.asarray(k, float).ravel(), np.eye(3).ravel(), p.ravel())))
        return self.t("sensor_msgs/msg/CameraInfo")(header=self.header(ns, frame), height=height, width=width,
                                                    distortion_model=model, binning_x=0, binning_y=0, roi=roi,
                                                    **mats)

    def image(self, ns: int, frame: str, path: Path, form: str, distort):
        if form == "compressed" and distort is None:
            data = np.fromfile(path, np.uint8)
            fmt = "png" if path.suffix.lower() == ".png" else "jpeg"
            return self.t("sensor_msgs/msg/CompressedImage")(header=self.header(ns, frame), format=fmt, data=data)
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        bgr = distort(bgr) if distort else bgr
        if form == "compressed":
            return self.t("sensor_msgs/msg/CompressedImage")(header=self.header(ns, frame), format="png",
                                                             data=cv2.imencode(".png", bgr)[1].ravel())
        convert = {"rgb8": cv2.COLOR_BGR2RGB, "mono8": cv2.COLOR_BGR2GRAY, "bgra8": cv2.COLOR_BGR2BGRA,
                   "mono16": cv2.COLOR_BGR2GRAY}
        pixels = cv2.cvtColor(bgr, convert[form]) if form in convert else bgr
        if form == "mono16":
            pixels = pixels.astype("<u2") * 257
        h, w = pixels.shape[:2]
        data = np.ascontiguousarray(pixels).view(np.uint8).ravel()
        return self.t("sensor_msgs/msg/Image")(header=self.header(ns, frame), height=h, width=w, encoding=form,
                                               is_bigendian=0, step=len(data) // h, data=data)


def write_bag(recording: Path, out: Path, form: BagForm = BagForm(), distort=None) -> Path:
    """Write ``recording`` (a footage_writer folder, YAML rotation already a quaternion) as a bag at
    ``out`` (a folder for rosbag2, ``out`` itself for .mcap or .bag); returns the bag's path."""
    from rosbags.typesys import Stores, get_typestore

    ros1 = form.storage == "ros1"
    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    if ros1:  # Noetic's store lacks tf2_msgs; its definition as ROS 1 ships it
        from rosbags.typesys import get_types_from_msg

        store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    m = _Messages(store, ros1)
    calib = yaml.safe_load((recording / "calibration.yaml").read_text())
    images, poses = _images(recording), _poses(recording)
    t0 = min(images[0][1], poses[0][0])
    model, coeffs = form.distortion or ("plumb_bob", (0.0,) * 5)
    mount = m.tf([m.transform(t0, "base_link", form.camera_frame, calib["cam_to_vehicle"]["translation"],
                              calib["cam_to_vehicle"]["rotation"])])
    records = [] if form.drop_camera_link else [("/tf_static", "tf2_msgs/msg/TFMessage", t0, mount)]
    records.append(("/camera/camera_info", "sensor_msgs/msg/CameraInfo", t0,
                    m.camera_info(t0, form.camera_frame, calib["intrinsics"], calib["width"], calib["height"], model,
                                  coeffs)))
    for ns, xyz, wxyz in poses:
        records.append(("/tf", "tf2_msgs/msg/TFMessage", ns, m.tf([m.transform(ns, "odom", "base_link", xyz, wxyz)]))
                       if form.ego == "tf" else ("/odom", "nav_msgs/msg/Odometry", ns, m.odometry(ns, xyz, wxyz)))
    kind = "sensor_msgs/msg/CompressedImage" if form.images == "compressed" else "sensor_msgs/msg/Image"
    topic = "/camera/image_raw/compressed" if form.images == "compressed" else "/camera/image_raw"
    for i, (path, ns) in enumerate(images):
        msg = m.image(ns, form.camera_frame, path, form.images, distort)
        if form.encoding_at is not None and form.encoding_at[0] == i:
            msg.encoding = form.encoding_at[1]
        records.append((topic, kind, ns, msg))
    records.sort(key=lambda r: r[2])
    return _write(records, out, form.storage, store)


def _write(records, out: Path, storage: str, store) -> Path:
    if storage == "ros1":
        from rosbags.rosbag1 import Writer as Writer1

        writer, serialize = Writer1(out), store.serialize_ros1
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
        folder = out.with_name(out.stem + "-rosbag2") if storage == "mcap-file" else out
        writer, serialize = Writer(folder, version=9, storage_plugin=plugin), store.serialize_cdr
    conns: dict[str, object] = {}
    with writer:
        for topic, kind, ns, msg in records:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, kind, typestore=store)
            writer.write(conns[topic], ns, serialize(msg, kind))
    if storage == "mcap-file":  # the MCAP file alone, without its metadata.yaml
        inner = next(folder.glob("*.mcap"))
        shutil.move(inner, out)
        shutil.rmtree(folder)
    return out
