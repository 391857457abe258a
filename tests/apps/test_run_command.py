"""``run_command``: the rules between ``pedenv run``'s flags, each refused with one line before anything is read."""

from pathlib import Path

import pytest

from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions
from pedenv.apps.options import RecordingSource as Source
from pedenv.apps.run_command import check_single_recording, run_command
from pedenv.errors import InputError
from pedenv.recordings.bag_topics import BagOptions

FILES = {"images": Path("images"), "calibration": Path("calibration.yaml"), "ego_poses": Path("poses.csv")}


def _run(tmp_path, **given):
    """run_command with the defaults of ``pedenv run`` on :data:`FILES` but for the groups ``given``."""
    groups = {"source": Source(**FILES), "flags": OutputFlags(), "pose": PoseOptions(), "executor": ExecutorOptions(),
              "method": MethodOptions(), **given}
    return run_command(output=OutputOptions(tmp_path / "out"), **groups)


@pytest.mark.parametrize("given, message", [
    ({"source": Source(images=Path("x"), fps=10.0)},
     "--images, --fps: with --manifest each row names its recording's files and timing"),
    ({"source": Source(static=True)}, "--static: with --manifest each row names its recording's files and timing"),
    ({"flags": OutputFlags(mcap=Path("a.mcap"))},
     "--parquet, --rerun and --mcap are written by single-recording runs, not --manifest runs"),
    ({"realtime": True}, "--realtime and --device apply to single-recording runs, not --manifest runs"),
    ({"pose": PoseOptions(device="cpu")}, "--realtime and --device apply to single-recording runs"),
    ({"source": Source(bag=Path("drive.mcap"))},
     "--ros-out, --live and --bag are for single-recording runs, not --manifest runs"),
    ({"flags": OutputFlags(live=8765)}, "--ros-out, --live and --bag are for single-recording runs"),
    ({"flags": OutputFlags(ros=Path("ros.mcap"))}, "--ros-out, --live and --bag are for single-recording runs"),
])
def test_a_manifest_refuses_the_flags_of_single_recordings(tmp_path, given, message):
    given = {"source": Source(), **given}
    with pytest.raises(InputError, match="^" + message.replace("(", r"\(").replace(")", r"\)")):
        _run(tmp_path, manifest=tmp_path / "nowhere.yaml", **given)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("source, executor, message", [
    (Source(**FILES, bag_options=BagOptions(image_topic="/cam", world_frame="map")), ExecutorOptions(),
     "--image-topic, --world-frame apply to --bag"),
    (Source(images=Path("images"), ego_poses=Path("poses.csv")), ExecutorOptions(),
     "give --calibration (with --ego-poses, or without them a vehicle's ego poses are estimated from the images), "
     "or --static for a fixed camera (without --calibration it is estimated from the people it sees), or a --bag, "
     "or a --manifest of recordings"),
    (Source(bag=Path("drive.mcap"), static=True), ExecutorOptions(),
     "--bag holds the images, camera and ego poses: leave out --images, --video, --calibration, --ego-poses and "
     "--static"),
    (Source(bag=Path("drive.mcap"), video=Path("v.mp4")), ExecutorOptions(), "--bag holds the images"),
    (Source(**FILES), ExecutorOptions("ray"), "--executor, --address, --workers and --resume apply to --manifest runs"),
    (Source(**FILES), ExecutorOptions(resume=True), "--executor, --address, --workers and --resume apply to"),
    (Source(**FILES), ExecutorOptions(workers=2), "--executor, --address, --workers and --resume apply to"),
])
def test_a_single_recording_refuses_flags_that_do_not_go_together(tmp_path, source, executor, message):
    with pytest.raises(InputError, match="^" + message.replace("(", r"\(").replace(")", r"\)")):
        _run(tmp_path, source=source, executor=executor)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("source", [
    Source(**FILES),
    Source(images=Path("images"), calibration=Path("c.yaml"), static=True),  # a fixed camera needs no ego poses
    Source(bag=Path("drive.mcap"), bag_options=BagOptions(odometry_topic="/odom")),
])
def test_the_flags_of_one_recording_that_go_together_pass(source):
    check_single_recording(source, ExecutorOptions())


def test_a_single_recordings_missing_files_are_named_after_the_flags_are_checked(tmp_path):
    (tmp_path / "rec").mkdir()
    with pytest.raises(InputError, match="calibration.yaml"):
        _run(tmp_path, source=Source(images=tmp_path / "rec", calibration=tmp_path / "rec" / "calibration.yaml",
                                     ego_poses=tmp_path / "rec" / "poses.csv"))
    assert not (tmp_path / "out").exists()
