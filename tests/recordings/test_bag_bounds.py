"""Bags held to the bounds files have: bombs refused before they are decompressed or decoded,
values in the ranges of the calibration YAML and the ego poses CSV, counts that disagree said so.

Each case is the tiny synthetic bag of ``bag_tiny`` with one thing set wrong; each gives one
InputError line naming the bag (and the topic, message index and field where there is one).
"""

import json
import re
import sqlite3
import struct
import zlib

import numpy as np
import pytest
import yaml
from bag_tiny import IMAGE_TOPIC, INFO_TOPIC, K, camera_info, tiny_bag

from pedenv.errors import InputError
from pedenv.recordings.bag import load_bag_recording
from pedenv.recordings.bag_topics import BagOptions

from cli_in_process import pedenv

pytestmark = pytest.mark.ros


def _frames(path, options=None) -> int:
    rec = load_bag_recording(path, options)
    return sum(1 for _ in rec.frames())


def _error(path, options=None) -> str:
    with pytest.raises(InputError) as err:
        _frames(path, options)
    return str(err.value)


def _types():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE).types


def _png_header(width: int, height: int) -> np.ndarray:
    """A PNG whose header announces ``width`` x ``height`` RGB pixels (its data is one empty row)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    png = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(b"\0")) + chunk(b"IEND", b"")
    return np.frombuffer(png, np.uint8)


def _zero_images(width: int, height: int):
    def change(topic, _index, msg):
        if topic == IMAGE_TOPIC:
            msg.width, msg.height, msg.step = width, height, 3 * width
            msg.data = np.zeros(3 * width * height, np.uint8)
        if topic == INFO_TOPIC:
            msg.width, msg.height = width, height
        return msg
    return change


@pytest.mark.parametrize("width, height, message", [
    (30000, 30000, "the compressed image: the image has 900000000 pixels, above the limit of 64 megapixels"),
    (128, 96, "the image is 128x96 pixels, the CameraInfo says 64x48"),
])
def test_a_compressed_image_is_sized_from_its_header_before_it_is_decoded(tmp_path, monkeypatch, width, height,
                                                                           message):
    from PIL import Image

    # Pillow's own limit (its default) decides the wording of the bomb's line; ultralytics switches it
    # off once imported (tests/outputs/test_file_names.py checks both wordings), so fix it here
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 89_478_485)
    def bomb(topic, _index, msg):
        if topic == IMAGE_TOPIC:
            msg.data = _png_header(width, height)
        return msg

    bag = tiny_bag(tmp_path / "a.mcap", storage="mcap-file", images=1, encoding="compressed", change=bomb)
    assert _error(bag).startswith(f"{bag}: topic {IMAGE_TOPIC} message 0: {message}")


@pytest.mark.parametrize("storage, compression, message", [
    ("mcap-file", "chunks", r"a chunk at file offset \d+ holds 2703246 bytes uncompressed \(\d+ compressed\), more "
                            r"than bag.max_message_bytes \(1048576\); a decompression bomb or a corrupt size field"),
    ("sqlite3", "message", r"topic /camera/image_raw message 0: decompresses to more than bag.max_message_bytes "
                           r"\(1048576\) from \d+ bytes; a decompression bomb or a runaway message"),
])
def test_compressed_chunks_and_messages_are_bounded_before_they_are_decompressed(tmp_path, storage, compression,
                                                                                  message):
    bag = tiny_bag(tmp_path / ("a.mcap" if storage == "mcap-file" else "a"), storage=storage, images=1,
                   compression=compression, change=_zero_images(1000, 900))
    assert re.fullmatch(f"{re.escape(str(bag))}: {message}", _error(bag, BagOptions(max_message_bytes=2**20)))
    assert _frames(bag) == 1  # within the default bound: read


def test_a_file_compressed_bag_is_decompressed_into_bounded_temporary_space(tmp_path, monkeypatch):
    monkeypatch.setenv("TMPDIR", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", None)
    monkeypatch.setattr("pedenv.recordings.bag_bounds.MIN_TEMPORARY_BYTES", 2**20)  # the bomb below is 8 MB
    small = tiny_bag(tmp_path / "small", compression="file")
    assert _frames(small) == 3
    bomb = tiny_bag(tmp_path / "bomb", images=3, compression="file", change=_zero_images(1000, 900))
    size = (bomb / "bomb.db3.zstd").stat().st_size
    assert _error(bomb) == (
        f"{bomb}: bomb.db3.zstd decompresses to more than 10 times the bag's {size} bytes (at least 1 MiB; "
        "pedenv.recordings.bag_bounds.MAX_FILE_DECOMPRESSION_RATIO) or than the free temporary disk: a decompression "
        "bomb, or decompress the bag yourself")
    assert list((tmp_path / "tmp").iterdir()) == []  # the temporary copies are gone


def _info(**fields):
    t = _types()

    def change(topic, _index, msg):
        return camera_info(t, 0, **fields) if topic == INFO_TOPIC else msg
    return change


def _k(entries):
    k = np.array(K)
    for (i, j), v in entries.items():
        k[i, j] = v
    return k


@pytest.mark.parametrize("fields, message", [
    ({"width": 20000, "height": 20000}, "CameraInfo image size 20000x20000 is above the limit of 64 megapixels"),
    ({"width": 2**32 - 1}, "CameraInfo field 'width' must be in [8, 20000] pixels, got 4.29497e+09"),
    ({"k": _k({(0, 0): 1e300})}, "CameraInfo focal length fx must be in [1, 100000] pixels, got 1e+300"),
    ({"k": _k({(1, 1): 1e-4})}, "CameraInfo focal length fy must be in [1, 100000] pixels, got 0.0001"),
    ({"k": _k({(0, 2): 1e300})}, "CameraInfo principal point cx must be in [-64, 128] pixels"),
    ({"k": _k({(0, 1): 1e12})}, "CameraInfo skew (intrinsics[0][1]) must be at most fx in size, got 1e+12"),
    ({"d": (0.1, 0.0, 0.0)}, "the plumb_bob model takes 5 coefficients (field d), got 3"),
    ({"d": (0.1,) * 100}, "the plumb_bob model takes 5 coefficients (field d), got 100"),
    ({"model": "equidistant", "d": (0.1,) * 5}, "the equidistant model takes 4 coefficients (field d), got 5"),
    ({"model": "rational_polynomial", "d": (0.1,) * 5}, "the rational_polynomial model takes 8 coefficients"),
    ({"d": (1e300, 0, 0, 0, 0)}, "distortion coefficient d[0] = 1e+300 is beyond 100 in size"),
])
def test_camera_info_gets_the_ranges_of_the_calibration_yaml(tmp_path, fields, message):
    bag = tiny_bag(tmp_path / "a", change=_info(**fields))
    assert _error(bag).startswith(f"{bag}: topic {INFO_TOPIC} message 0: {message}")


@pytest.mark.parametrize("encoding", ["yuyv", "uyvy"])
def test_paired_encodings_need_an_even_width(tmp_path, encoding):
    def odd(topic, _index, msg):
        if topic == IMAGE_TOPIC:
            msg.width, msg.step = 63, 126
            msg.data = msg.data[:126 * 48]
        if topic == INFO_TOPIC:
            msg.width = 63
        return msg

    bag = tiny_bag(tmp_path / "a", encoding=encoding, change=odd)
    assert _error(bag) == f"{bag}: topic {IMAGE_TOPIC} message 0: a {encoding} image needs an even width (pixels " \
                          "come in pairs), got 63"


def _far(topic_wanted, index_wanted, where):
    def change(topic, index, msg):
        if topic == topic_wanted and index == index_wanted:
            if topic == "/odom":
                msg.pose.pose.position.x = 1e20
            else:
                msg.transforms[0].transform.translation.__setattr__(where, 1e20 if topic == "/tf" else 1e6)
        return msg
    return change


@pytest.mark.parametrize("ego, topic, index, where, message", [
    ("tf", "/tf", 3, "x", "topic /tf message 3: transform 'odom' -> 'base_link': transform.translation.x = 1e+20 m "
                          "is beyond 1e+07 m from the origin"),
    ("odometry", "/odom", 2, "x", "topic /odom message 2: pose.pose.position.x = 1e+20 m is beyond 1e+07 m"),
    ("tf", "/tf_static", 0, "z", "the tf chain camera_optical -> base_link puts the camera 1e+06 m from the vehicle "
                                 "origin; at most 100 m"),
])
def test_tf_and_odometry_get_the_ranges_of_the_ego_poses_csv(tmp_path, ego, topic, index, where, message):
    bag = tiny_bag(tmp_path / "a", ego=ego, change=_far(topic, index, where))
    assert _error(bag).startswith(f"{bag}: {message}")


def test_a_camera_frame_given_as_the_vehicle_frame(tmp_path):
    bag = tiny_bag(tmp_path / "a")
    assert _error(bag, BagOptions(vehicle_frame="camera_optical")) == (
        f"{bag}: the tf chain camera_optical -> camera_optical has the camera look 90 degrees up from the vehicle's "
        "horizon; at most 60 (the vehicle frame must be x forward, z up: is 'camera_optical' the vehicle? "
        "--vehicle-frame)")


def _edit_metadata(bag, edit):
    path = bag / "metadata.yaml"
    data = yaml.safe_load(path.read_text())
    for topic in data["rosbag2_bagfile_information"]["topics_with_message_count"]:
        edit(topic)
    path.write_text(yaml.safe_dump(data))


def _images_count(value):
    def edit(topic):
        if topic["topic_metadata"]["name"] == IMAGE_TOPIC:
            topic["message_count"] = value
    return edit


@pytest.mark.parametrize("count", [-7, "abc", 1.5])
def test_a_message_count_that_is_no_count(tmp_path, monkeypatch, capsys, count):
    bag = tiny_bag(tmp_path / "a")
    _edit_metadata(bag, _images_count(count))
    line = f"{bag}: metadata.yaml gives topic {IMAGE_TOPIC} a message_count of {count!r}, not a count (a whole " \
           "number, 0 or more)"
    assert _error(bag) == line
    code, out, err = pedenv(monkeypatch, capsys, "inspect-bag", bag)
    assert (code, out, err) == (2, "", f"error: {line}\n")


def test_a_type_that_disagrees_with_the_storage(tmp_path):
    bag = tiny_bag(tmp_path / "a")

    def edit(topic):
        if topic["topic_metadata"]["name"] == IMAGE_TOPIC:
            topic["topic_metadata"]["type"] = "sensor_msgs/msg/CompressedImage"
    _edit_metadata(bag, edit)
    assert _error(bag) == (f"{bag}: metadata.yaml gives topic {IMAGE_TOPIC} the type sensor_msgs/msg/CompressedImage, "
                           "its storage holds sensor_msgs/msg/Image: the two disagree (an edited metadata.yaml?)")


@pytest.mark.parametrize("damage", ["rows", "count"])
def test_counts_that_disagree_are_warned_about_and_the_storage_read(tmp_path, damage):
    bag = tiny_bag(tmp_path / "a")
    if damage == "rows":  # 2 of the 3 image rows lost
        with sqlite3.connect(bag / "a.db3") as db:
            db.execute("DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = ?) AND timestamp > 1",
                       (IMAGE_TOPIC,))
        counts, held = "3", 1
    else:
        _edit_metadata(bag, _images_count(10**15))
        counts, held = "1000000000000000", 3
    line = (f"{bag}: the storage holds fewer or more messages than metadata.yaml counts ({IMAGE_TOPIC} {held} of "
            f"{counts}): messages lost or the metadata edited; reading what the storage holds")
    with pytest.warns(UserWarning) as caught:
        rec = load_bag_recording(bag)
    assert [str(w.message) for w in caught] == [line]
    assert len(rec) == held and sum(1 for _ in rec.frames()) == held
    assert rec.ended_early == line


def test_a_bomb_is_one_line_from_pedenv_run(tmp_path, monkeypatch, capsys):
    bag = tiny_bag(tmp_path / "a", change=_info(width=20000, height=20000))
    code, out, err = pedenv(monkeypatch, capsys, "run", "--bag", bag, "--output", tmp_path / "out")
    assert code == 2 and "Traceback" not in out + err
    assert err.splitlines()[-1] == (f"error: {bag}: topic {INFO_TOPIC} message 0: CameraInfo image size 20000x20000 "
                                    "is above the limit of 64 megapixels (pedenv.images.MAX_IMAGE_PIXELS)")


@pytest.mark.parametrize("storage, compression", [("mcap-file", "chunks"), ("sqlite3", "message")])
def test_inspect_bag_takes_the_rates_from_the_indexes(tmp_path, monkeypatch, capsys, storage, compression):
    """Nothing decompressed for the topic list: the MCAP message indexes, a sqlite3 query."""
    from pedenv.recordings.bag_source import BagSource

    bag = tiny_bag(tmp_path / ("a.mcap" if storage == "mcap-file" else "a"), storage=storage, compression=compression)
    monkeypatch.setattr(BagSource, "log_spans", None)  # reading every message is not needed
    code, out, _ = pedenv(monkeypatch, capsys, "inspect-bag", bag)
    assert code == 0
    assert "  /camera/image_raw    sensor_msgs/Image  3 msgs  10.00 Hz" in out.splitlines()
    assert "  /tf                  tf2_msgs/TFMessage  7 msgs  20.00 Hz" in out.splitlines()


@pytest.mark.parametrize("fmt", ["BZ2", "LZ4"])
def test_a_compressed_ros1_chunk_is_bounded(tmp_path, fmt):
    """ROS 1 chunks do not keep their uncompressed size in rosbags: each is cut at max_message_bytes."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    t = store.types
    header = t["std_msgs/msg/Header"](seq=0, stamp=t["builtin_interfaces/msg/Time"](sec=0, nanosec=0),
                                      frame_id="camera_optical")
    roi = t["sensor_msgs/msg/RegionOfInterest"](x_offset=0, y_offset=0, height=0, width=0, do_rectify=False)
    info = t["sensor_msgs/msg/CameraInfo"](header=header, height=48, width=64, distortion_model="plumb_bob",
                                           D=np.zeros(5), K=np.array(K).ravel(), R=np.eye(3).ravel(),
                                           P=np.zeros(12), binning_x=0, binning_y=0, roi=roi)
    zeros = t["sensor_msgs/msg/Image"](header=header, height=900, width=1000, encoding="rgb8", is_bigendian=0,
                                       step=3000, data=np.zeros(2_700_000, np.uint8))
    bag = tmp_path / "a.bag"
    writer = Writer(bag)
    writer.set_compression(getattr(Writer.CompressionFormat, fmt))
    writer.chunk_threshold = 2**23  # one chunk holding both messages
    with writer:
        for topic, kind, msg in ((INFO_TOPIC, "sensor_msgs/msg/CameraInfo", info),
                                 (IMAGE_TOPIC, "sensor_msgs/msg/Image", zeros)):
            conn = writer.add_connection(topic, kind, typestore=store)
            writer.write(conn, 1, store.serialize_ros1(msg, kind))
    assert re.fullmatch(rf"{re.escape(str(bag))}: first chunk: a {fmt.lower()} chunk of \d+ bytes "
                        r"decompresses to more than bag.max_message_bytes \(1048576\); a decompression bomb or a "
                        "corrupt chunk", _error(bag, BagOptions(max_message_bytes=2**20)))
    assert "has no transform" in _error(bag)  # within the default bound the chunk is read (this bag has no /tf)


@pytest.mark.onnx_model
def test_a_bag_short_of_its_count_says_so_in_run_json(tmp_path, monkeypatch, capsys):
    bag = tiny_bag(tmp_path / "a")
    with sqlite3.connect(bag / "a.db3") as db:  # 2 of the 3 image rows lost
        db.execute("DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = ?) AND timestamp > 1",
                   (IMAGE_TOPIC,))
    with pytest.warns(UserWarning):
        code, _, err = pedenv(monkeypatch, capsys, "run", "--bag", bag, "--output", tmp_path / "out",
                              "--detection", "fast")
    assert code == 0, err
    summary = json.loads((tmp_path / "out" / "run.json").read_text())
    assert summary["frames_done"] == 1
    assert summary["ended_early"].startswith(f"{bag}: the storage holds fewer or more messages than metadata.yaml")
