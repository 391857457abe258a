"""``pedenv run --bag`` on bags of the real KITTI and MOT17 samples: the same environment.jsonl as
the image-folder recording, ``--ros-out`` beside it, and a bad image stopping the run after the frames before it."""

import csv

import pytest
from bag_samples import BagForm, kitti_recording, quaternion_calibration, write_bag

from pedenv.outputs.jsonl import read_environment
from pedenv.recordings.footage_writer import write_mot17_recording

from cli_in_process import pedenv
from shared_paths import REAL_SAMPLES

pytestmark = [pytest.mark.ultralytics, pytest.mark.onnx_model, pytest.mark.slow, pytest.mark.ros]

NAMES = {"ros1": "images.bag", "mcap-file": "images.mcap"}


@pytest.fixture(scope="module", autouse=True)
def models():
    """The ONNX models in the user's cache (exported once if missing), as `pedenv run` finds them."""
    import os

    from pedenv.pose.models import prepare_models

    os.environ["YOLO_OFFLINE"] = "1"
    prepare_models()


def _run(monkeypatch, capsys, out, *source, detection="far"):
    code, stdout, stderr = pedenv(monkeypatch, capsys, "run", *source, "--output", out, "--detection", detection)
    return code, stdout, stderr


def _folder(rec):
    return ("--images", rec / "images", "--calibration", rec / "calibration.yaml", "--ego-poses", rec / "ego_poses.csv")


@pytest.fixture(scope="module")
def kitti(tmp_path_factory):
    return kitti_recording(tmp_path_factory.mktemp("kitti") / "rec", REAL_SAMPLES)


@pytest.fixture(scope="module")
def mot17(tmp_path_factory):
    """MOT17-09's first 3 frames."""
    rec = write_mot17_recording(REAL_SAMPLES / "mot17" / "MOT17-09-FRCNN", tmp_path_factory.mktemp("mot") / "rec",
                                pitch_down_deg=10.0)
    quaternion_calibration(rec)
    table = rec / "images" / "timestamps.csv"
    rows = list(csv.reader(table.open()))
    for name, _ in rows[4:]:
        (rec / "images" / name).unlink()
    with table.open("w", newline="") as f:
        csv.writer(f).writerows(rows[:4])
    return rec


def test_kitti_bags_give_the_environment_of_the_image_folder(kitti, tmp_path, monkeypatch, capsys):
    assert _run(monkeypatch, capsys, tmp_path / "ref", *_folder(kitti))[0] == 0
    reference = (tmp_path / "ref" / "environment.jsonl").read_text()
    assert len(reference.splitlines()) == 3 and '"track_id"' in reference
    for storage, images in (("mcap", "rgb8"), ("sqlite3", "compressed"), ("ros1", "bgr8")):
        (tmp_path / storage).mkdir()
        bag = write_bag(kitti, tmp_path / storage / NAMES.get(storage, "images"), BagForm(storage, images))
        out = tmp_path / f"out-{storage}"
        extra = ("--ros-out", out / "ros.mcap") if storage == "mcap" else ()
        code, stdout, _ = _run(monkeypatch, capsys, out, "--bag", bag, *extra)
        assert code == 0 and stdout.startswith("3 frames ->")
        assert (out / "environment.jsonl").read_text() == reference, storage
    from pedenv.recordings.bag_source import BagSource

    lines = read_environment(tmp_path / "ref" / "environment.jsonl")
    with BagSource(tmp_path / "out-mcap" / "ros.mcap") as ros:
        arrays = [m.msg for m in ros.messages(["/pedestrians"])]
    for line, msg in zip(lines, arrays, strict=True):
        got = [(d.id, [round(v, 3) for v in (d.results[0].pose.pose.position.x, d.results[0].pose.pose.position.y)])
               for d in msg.detections]
        assert got == [(str(p["track_id"]), p["position"][:2]) for p in line["pedestrians"]]


def test_a_mot17_bag_of_jpeg_files_gives_the_same_environment(mot17, tmp_path, monkeypatch, capsys):
    assert _run(monkeypatch, capsys, tmp_path / "ref", *_folder(mot17), detection="fast")[0] == 0
    bag = write_bag(mot17, tmp_path / "images.mcap", BagForm("mcap-file", "compressed", ego="odometry"))
    # served live too (no viewer connects; the run goes on the same)
    assert _run(monkeypatch, capsys, tmp_path / "bag", "--bag", bag, "--live", "--live-port", "0",
                detection="fast")[0] == 0
    reference = (tmp_path / "ref" / "environment.jsonl").read_text()
    assert len(reference.splitlines()) == 3
    assert (tmp_path / "bag" / "environment.jsonl").read_text() == reference


def test_an_unknown_encoding_stops_the_run_after_the_frames_before_it(kitti, tmp_path, monkeypatch, capsys):
    bag = write_bag(kitti, tmp_path / "images.bag", BagForm("ros1", "rgb8", encoding_at=(2, "rgb9")))
    code, _, stderr = _run(monkeypatch, capsys, tmp_path / "out", "--bag", bag, detection="fast")
    assert code == 2
    errors = [line for line in stderr.splitlines() if "error" in line]
    assert errors == [f"error: {bag}: topic /camera/image_raw message 2: unknown image encoding 'rgb9' "
                                   "(known: rgb8, bgr8, rgba8, bgra8, mono8, 8UC1, 8UC3, mono16, 16UC1, bayer_rggb8, "
                                   "bayer_bggr8, bayer_gbrg8, bayer_grbg8, yuv422, uyvy, yuv422_yuy2, yuyv)"]
    assert len(read_environment(tmp_path / "out" / "environment.jsonl")) == 2
