"""``pedenv inspect-bag`` and the flags of ``pedenv run --bag``, as a user types them."""

import json

import pytest
from bag_samples import BagForm, quaternion_calibration, write_bag

from pedenv.recordings.footage_writer import write_kitti_recording

from cli_in_process import pedenv
from shared_paths import REAL_SAMPLES

pytestmark = pytest.mark.ros  # the ros extra (rosbags, mcap)


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    folder = tmp_path_factory.mktemp("kitti")
    rec = write_kitti_recording(REAL_SAMPLES / "kitti" / "tracking_mini" / "training", "0016", folder / "rec")
    quaternion_calibration(rec)
    return write_bag(rec, folder / "drive.bag", BagForm("ros1", "compressed", ego="odometry"))


def test_inspect_bag_prints_topics_rates_tf_and_what_run_uses(bag, monkeypatch, capsys):
    code, out, _ = pedenv(monkeypatch, capsys, "inspect-bag", bag)
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == f"{bag} (ros1)"
    assert "  /camera/image_raw/compressed  sensor_msgs/CompressedImage  3 msgs  2.00 Hz" in lines
    assert "  /odom                         nav_msgs/Odometry  209 msgs  10.00 Hz" in lines
    assert lines[lines.index("tf frames:") + 1] == "  base_link -> camera_optical (static)"
    run = lines[lines.index("pedenv run --bag would use:") + 1:]
    assert run[:6] == ["  images: /camera/image_raw/compressed", "  camera_info: /camera/camera_info", "  ego: /odom",
                       "  camera_frame: camera_optical", "  vehicle_frame: base_link", "  world_frame: odom"]
    code, out, _ = pedenv(monkeypatch, capsys, "inspect-bag", bag, "--json", "--world-frame", "map")
    summary = json.loads(out)
    assert code == 0 and summary["topics"][0] == {"name": "/camera/camera_info", "type": "sensor_msgs/CameraInfo",
                                                  "count": 1, "rate_hz": None}
    assert summary["run_error"] == (f"{bag}: --world-frame map, but the poses of /odom are of 'odom' "
                                    "(header.frame_id); leave out --world-frame or give another --odometry-topic")


@pytest.mark.parametrize("args, error", [
    (["--images", "x"], "error: --bag holds the images, camera and ego poses: leave out --images, --video, "
                        "--calibration, --ego-poses and --static"),
    (["--manifest", "m.csv"], "error: --ros-out, --live and --bag are for single-recording runs, not --manifest runs"),
])
def test_run_refuses_flags_that_do_not_go_with_a_bag(bag, tmp_path, monkeypatch, capsys, args, error):
    code, _, err = pedenv(monkeypatch, capsys, "run", "--bag", bag, "--output", tmp_path / "out", *args)
    assert code == 2 and err.splitlines() == [error]
    assert not (tmp_path / "out").exists()


def test_bag_flags_without_a_bag(tmp_path, monkeypatch, capsys):
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", "x", "--image-topic", "/cam", "--vehicle-frame",
                          "base", "--output", tmp_path / "out")
    assert code == 2 and err.splitlines() == ["error: --image-topic, --vehicle-frame apply to --bag"]
