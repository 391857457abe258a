"""ROS bags of the real KITTI and MOT17 samples read back as the same Frames as their image-folder recordings."""

import cv2
import numpy as np
import pytest
from bag_samples import BagForm, quaternion_calibration, write_bag

from pedenv.errors import InputError
from pedenv.recordings.bag import load_bag_recording
from pedenv.recordings.bag_topics import BagOptions
from pedenv.recordings.footage import load_recording
from pedenv.recordings.footage_writer import write_kitti_recording, write_mot17_recording

from shared_paths import REAL_SAMPLES

pytestmark = pytest.mark.ros  # the ros extra (rosbags, mcap)

KITTI = REAL_SAMPLES / "kitti" / "tracking_mini" / "training"
MOT17 = REAL_SAMPLES / "mot17" / "MOT17-09-FRCNN"
NAMES = {"ros1": "images.bag", "mcap-file": "images.mcap"}


def _recording(folder):
    return load_recording(calibration=folder / "calibration.yaml", ego_poses=folder / "ego_poses.csv",
                          images=folder / "images")


@pytest.fixture(scope="module")
def kitti(tmp_path_factory):
    """KITTI tracking 0016 (3 frames, ORB-SLAM3 poses) as an image-folder recording, rotation as a quaternion."""
    folder = write_kitti_recording(KITTI, "0016", tmp_path_factory.mktemp("kitti") / "rec")
    quaternion_calibration(folder)
    return folder


@pytest.fixture(scope="module")
def mot17(tmp_path_factory):
    """MOT17-09 (6 JPEG frames, a camera 1.5 m up pitched 10 degrees down, a standing ego)."""
    folder = write_mot17_recording(MOT17, tmp_path_factory.mktemp("mot17") / "rec", pitch_down_deg=10.0)
    quaternion_calibration(folder)
    return folder


def _bag(recording, tmp_path, **form):
    form = BagForm(**form)
    (tmp_path / form.storage).mkdir(exist_ok=True)
    return write_bag(recording, tmp_path / form.storage / NAMES.get(form.storage, "images"), form)


def _same_frames(reference, bag, lossless: bool = True) -> None:
    ref, got = list(reference.frames()), list(bag.frames())
    assert [f.index for f in got] == [f.index for f in ref] and len(ref) >= 3
    for a, b in zip(ref, got):
        assert b.timestamp == a.timestamp and b.scene == a.scene == "images"
        assert np.array_equal(b.ego.matrix, a.ego.matrix)
        assert np.array_equal(b.camera.intrinsics, a.camera.intrinsics)
        assert np.array_equal(b.camera.cam_to_vehicle, a.camera.cam_to_vehicle)
        if lossless:
            assert np.array_equal(b.image, a.image)


@pytest.mark.parametrize("storage, images, ego", [
    ("mcap", "rgb8", "tf"), ("sqlite3", "compressed", "tf"), ("mcap-file", "bgr8", "odometry"),
    ("ros1", "rgb8", "tf"), ("ros1", "compressed", "odometry"), ("sqlite3", "bgra8", "tf"),
])
def test_a_kitti_bag_gives_the_frames_of_the_image_folder(kitti, tmp_path, storage, images, ego):
    bag = load_bag_recording(_bag(kitti, tmp_path, storage=storage, images=images, ego=ego))
    _same_frames(_recording(kitti), bag)
    assert len(bag) == 3 and bag.choice.camera_frame == "camera_optical"
    assert (bag.choice.vehicle_frame, bag.choice.world_frame) == ("base_link", "odom")
    assert bag.choice.odometry_topic == ("/odom" if ego == "odometry" else None)


def test_a_mot17_bag_of_jpeg_files_gives_the_same_pixels(mot17, tmp_path):
    _same_frames(_recording(mot17), load_bag_recording(_bag(mot17, tmp_path, storage="mcap", images="compressed")))


@pytest.mark.parametrize("images", ["mono8", "mono16"])
def test_grey_images_come_as_the_grey_of_the_colour_frames(kitti, tmp_path, images):
    ref = [f.image for f in _recording(kitti).frames()]
    got = [f.image for f in load_bag_recording(_bag(kitti, tmp_path, images=images)).frames()]
    for a, b in zip(ref, got):
        grey = cv2.cvtColor(a, cv2.COLOR_RGB2GRAY)
        assert b.shape == a.shape and np.array_equal(b[..., 0], b[..., 2])
        assert np.abs(b[..., 0].astype(int) - grey).max() <= 1  # mono16 = grey * 257, back by >> 8


def _distorter(k, coeffs, model, size):
    """The distorted image of an undistorted one: each distorted pixel samples its undistorted point."""
    w, h = size
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    pix = np.stack([u.ravel(), v.ravel()], axis=1)[:, None, :]
    d = np.array(coeffs)
    undistort = cv2.fisheye.undistortPoints if model == "equidistant" else cv2.undistortPoints
    und = undistort(pix, k, d, P=k)
    mx, my = (und[:, 0, i].reshape(h, w).astype(np.float32) for i in (0, 1))
    return lambda bgr: cv2.remap(bgr, mx, my, cv2.INTER_CUBIC, borderMode=cv2.BORDER_REPLICATE)


@pytest.mark.parametrize("model, coeffs", [
    ("plumb_bob", (-0.30, 0.10, 0.001, -0.001, 0.0)),
    ("rational_polynomial", (-0.25, 0.08, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0)),
    ("equidistant", (0.05, -0.01, 0.002, 0.0)),
])
def test_a_distorted_bag_is_undistorted_back_within_a_pixel(kitti, tmp_path, model, coeffs):
    ref = list(_recording(kitti).frames())
    cam = ref[0].camera
    distort = _distorter(cam.intrinsics, coeffs, model, (cam.width, cam.height))
    form = BagForm(images="rgb8", distortion=(model, coeffs))
    bag = load_bag_recording(write_bag(kitti, tmp_path / "images", form, distort=distort))
    assert bag.camera_model.distorted and bag.camera_model.model == model
    for a, b in zip(ref, bag.frames()):
        raw = cv2.cvtColor(distort(cv2.cvtColor(a.image, cv2.COLOR_RGB2BGR)), cv2.COLOR_BGR2RGB)
        inner = (slice(60, cam.height - 60), slice(150, cam.width - 150))  # away from the border lost to the warp
        grey_a, grey_b, grey_raw = (cv2.cvtColor(x, cv2.COLOR_RGB2GRAY)[inner].astype(np.float64)
                                    for x in (a.image, b.image, raw))
        shifts = []
        for r in range(0, grey_a.shape[0] - 127, 64):  # each 128 px patch: where it moved
            for c in range(0, grey_a.shape[1] - 127, 128):
                (dx, dy), _ = cv2.phaseCorrelate(grey_a[r:r + 128, c:c + 128], grey_b[r:r + 128, c:c + 128])
                shifts.append(np.hypot(dx, dy))
        assert np.max(shifts) < 1.0  # undistorted: every patch back within a pixel of the truth
        assert np.mean(np.abs(grey_b - grey_a)) < 0.5 * np.mean(np.abs(grey_raw - grey_a))


def test_a_camera_link_missing_from_tf_is_one_line_listing_the_tree(kitti, tmp_path):
    bag = _bag(kitti, tmp_path, drop_camera_link=True)
    with pytest.raises(InputError) as err:
        load_bag_recording(bag)
    assert str(err.value) == (f"{bag}: the camera frame 'camera_optical' (/camera/camera_info) has no transform in "
                              "/tf_static or /tf; the bag holds: odom->base_link")


def test_the_user_names_the_frames_when_the_tree_holds_more(kitti, tmp_path):
    bag = _bag(kitti, tmp_path)
    rec = load_bag_recording(bag, BagOptions(vehicle_frame="base_link", world_frame="odom",
                                             image_topic="/camera/image_raw"))
    assert rec.choice.world_frame == "odom"
    with pytest.raises(InputError, match=r"--image-topic /nope is not one of the bag's image topics; it holds: "
                                         r"/camera/camera_info \(sensor_msgs/CameraInfo, 1\); /camera/image_raw"):
        load_bag_recording(bag, BagOptions(image_topic="/nope"))
    with pytest.raises(InputError, match="no transform chain from 'base_link' up to 'map'.*base_link -> odom"):
        load_bag_recording(bag, BagOptions(world_frame="map"))


def test_a_sqlite3_bag_without_message_definitions_is_read_with_humble_types(kitti, tmp_path):
    """rosbag2 before Iron stored no message definitions in its sqlite3 file."""
    import sqlite3

    bag = _bag(kitti, tmp_path, storage="sqlite3")
    with sqlite3.connect(next(bag.glob("*.db3"))) as db:
        assert db.execute("DELETE FROM message_definitions").rowcount == 3  # TFMessage, CameraInfo, Image
    from pedenv.recordings.bag_source import BagSource

    with BagSource(bag) as source:
        assert all(not c.msgdef.data for c in source.connections)
    _same_frames(_recording(kitti), load_bag_recording(bag))
