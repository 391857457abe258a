"""Bad bags: one InputError line naming the bag (and the topic and message index where there is one)."""

import shutil
import struct

import pytest
from bag_samples import BagForm, _Messages, kitti_recording, write_bag

from pedenv.errors import InputError
from pedenv.recordings.bag import load_bag_recording
from pedenv.recordings.bag_topics import BagOptions

from shared_paths import REAL_SAMPLES

pytestmark = pytest.mark.ros  # the ros extra (rosbags, mcap)


@pytest.fixture(scope="module")
def kitti(tmp_path_factory):
    return kitti_recording(tmp_path_factory.mktemp("kitti") / "rec", REAL_SAMPLES)


def _frames(path, options=None) -> int:
    """Frames read before the error (the error re-raised with the count in ``done``)."""
    done = 0
    try:
        for _ in load_bag_recording(path, options).frames():
            done += 1
    except InputError as exc:
        exc.done = done
        raise
    return done


@pytest.mark.parametrize("storage, name, why", [
    ("ros1", "a.bag", "Bag index looks damaged"),
    ("sqlite3", "a", "database disk image is malformed"),
])
def test_a_truncated_bag_that_cannot_be_read(kitti, tmp_path, storage, name, why):
    bag = write_bag(kitti, tmp_path / name, BagForm(storage))
    file = bag if bag.is_file() else next(bag.glob("*.db3"))
    file.write_bytes(file.read_bytes()[:int(file.stat().st_size * 0.6)])
    with pytest.raises(InputError, match=rf"^{bag}: cannot open the bag \(truncated or damaged\?\): .*{why}"):
        _frames(bag)


@pytest.mark.parametrize("storage, name", [("mcap-file", "a.mcap"), ("mcap", "a")])
@pytest.mark.parametrize("kept, done", [(0.6, 1), (0.8, 2)])
def test_a_cut_mcap_bag_gives_the_frames_before_the_cut(kitti, tmp_path, storage, name, kept, done):
    """A recorder that crashed: no summary, no footer, the last record cut in half."""
    bag = write_bag(kitti, tmp_path / name, BagForm(storage))
    file = bag if bag.is_file() else next(bag.glob("*.mcap"))
    file.write_bytes(file.read_bytes()[:int(file.stat().st_size * kept)])
    with pytest.raises(InputError) as err:
        _frames(bag)
    assert str(err.value) == (f"{bag}: the file is cut off after topic /camera/image_raw message {done - 1} "
                              "(truncated: EndOfFile); the messages before it were read")
    assert err.value.done == done


def test_a_size_field_that_lies_names_the_message_after_the_frames_before_it(kitti, tmp_path):
    bag = write_bag(kitti, tmp_path / "a.mcap", BagForm("mcap-file"))
    data = bytearray(bag.read_bytes())
    length = struct.pack("<I", 370 * 1224 * 3)  # the data length of each Image (uncompressed chunks)
    second = data.find(length, data.find(length) + 1)
    data[second:second + 4] = struct.pack("<I", 0x7FFFFF00)
    bag.write_bytes(bytes(data))
    with pytest.raises(InputError, match=rf"^{bag}: topic /camera/image_raw message 1 \(sensor_msgs/msg/Image\) cannot "
                                         r"be decoded .*Invalid sequence length 2147483392") as err:
        _frames(bag)
    assert err.value.done == 1


def test_an_image_whose_step_lies(kitti, tmp_path):
    seen = []

    def lie(topic, msg):
        if topic == "/camera/image_raw":
            seen.append(topic)
            msg.step += 4 if len(seen) == 2 else 0
        return msg

    bag = _rewrite(write_bag(kitti, tmp_path / "a", BagForm("sqlite3")), tmp_path / "b", change=lie)
    with pytest.raises(InputError, match=rf"^{bag}: topic /camera/image_raw message 1: image fields disagree: "
                                         r"1224x370 rgb8, step 3676, 1358640 data bytes") as err:
        _frames(bag)
    assert err.value.done == 1


def test_a_huge_message(kitti, tmp_path):
    bag = write_bag(kitti, tmp_path / "a", BagForm("sqlite3"))
    with pytest.raises(InputError, match=rf"^{bag}: topic /camera/image_raw message 0: 1358700 bytes, more than "
                                         r"bag.max_message_bytes \(1048576\)"):
        _frames(bag, BagOptions(max_message_bytes=2**20))
    with pytest.raises(InputError, match=r"bag.max_message_bytes must be in \[1024, 2\*\*40\], got 10"):
        _frames(bag, BagOptions(max_message_bytes=10))


def _rewrite(bag, out, keep=lambda topic: True, change=lambda topic, msg: msg):  # noqa: ARG005 - keep all, change none
    """A copy of the rosbag2 ``bag`` with only the topics ``keep`` accepts, each message through ``change``."""
    from rosbags.rosbag2 import Reader, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with Reader(bag) as reader, Writer(out, version=9) as writer:
        conns = {c.topic: writer.add_connection(c.topic, c.msgtype, typestore=store)
                 for c in reader.connections if keep(c.topic)}
        for c, ns, raw in reader.messages():
            if keep(c.topic):
                msg = change(c.topic, store.deserialize_cdr(raw, c.msgtype))
                writer.write(conns[c.topic], ns, store.serialize_cdr(msg, c.msgtype))
    return out


@pytest.mark.parametrize("drop, message", [
    ("/camera/image_raw", "no image topics, give --image-topic; the bag holds: /camera/camera_info "
                          "(sensor_msgs/CameraInfo, 1); /tf (tf2_msgs/TFMessage, 209); "
                          "/tf_static (tf2_msgs/TFMessage, 1)"),
    ("/camera/camera_info", "no CameraInfo topics, give --camera-info-topic; the bag holds: /camera/image_raw "
                            "(sensor_msgs/Image, 3); /tf (tf2_msgs/TFMessage, 209); "
                            "/tf_static (tf2_msgs/TFMessage, 1)"),
])
def test_no_images_or_no_camera_info(kitti, tmp_path, drop, message):
    bag = _rewrite(write_bag(kitti, tmp_path / "a", BagForm("sqlite3")), tmp_path / "b", lambda t: t != drop)
    with pytest.raises(InputError) as err:
        _frames(bag)
    assert str(err.value) == f"{bag}: {message}"


def test_a_tf_loop(kitti, tmp_path):
    from rosbags.typesys import Stores, get_typestore

    messages = _Messages(get_typestore(Stores.ROS2_HUMBLE), False)

    def loop(topic, msg):
        if topic == "/tf_static":  # camera_optical -> odom closes odom -> base_link -> camera_optical
            msg.transforms.append(messages.transform(0, "camera_optical", "odom", (0, 0, 0), (1, 0, 0, 0)))
        return msg

    bag = _rewrite(write_bag(kitti, tmp_path / "a", BagForm("sqlite3")), tmp_path / "b", change=loop)
    with pytest.raises(InputError) as err:
        _frames(bag)
    assert str(err.value) == f"{bag}: the tf tree has a loop: camera_optical -> base_link -> odom -> camera_optical"


@pytest.mark.parametrize("topic, message", [
    ("/camera/image_raw", "topic /camera/image_raw message 2: stamps go backwards: 0.100000000 s is not after the "
                          "previous image's 0.700000000 s"),
    ("/tf", "topic /tf message 5: stamps go backwards: 'odom' -> 'base_link' at 0.100000000 s after 0.400000000 s"),
])
def test_stamps_going_backwards(kitti, tmp_path, topic, message):
    seen = {}

    def back(t, msg):
        seen[t] = seen.get(t, -1) + 1
        if t == topic and seen[t] == (2 if t == "/camera/image_raw" else 5):
            stamp = msg.header.stamp if t != "/tf" else msg.transforms[0].header.stamp
            stamp.sec, stamp.nanosec = 0, 100_000_000
        return msg

    bag = _rewrite(write_bag(kitti, tmp_path / "a", BagForm("sqlite3")), tmp_path / "b", change=back)
    with pytest.raises(InputError) as err:
        _frames(bag)
    assert str(err.value) == f"{bag}: {message}"
    assert getattr(err.value, "done", 0) == (2 if topic == "/camera/image_raw" else 0)


def test_not_a_bag(tmp_path):
    (tmp_path / "x.txt").write_text("hello")
    with pytest.raises(InputError, match=r"x.txt: not a bag \(a rosbag2 folder with metadata.yaml"):
        load_bag_recording(tmp_path / "x.txt")
    with pytest.raises(InputError, match="not a rosbag2 folder"):
        load_bag_recording(tmp_path)
    shutil.copy(tmp_path / "x.txt", tmp_path / "x.mcap")
    with pytest.raises(InputError, match=r"x.mcap: cannot open the bag \(truncated or damaged\?\): File magic"):
        load_bag_recording(tmp_path / "x.mcap")
