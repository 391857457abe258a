"""Manifests of recordings (CSV and YAML): rows read with their paths, every bad row one clear error."""

import pytest

from pedenv.errors import InputError
from pedenv.recordings.manifest import read_manifest


@pytest.fixture
def recordings(tmp_path):
    """Two recordings' files: an image folder and a video file, one calibration, poses each."""
    (tmp_path / "a" / "images").mkdir(parents=True)
    (tmp_path / "b").mkdir()
    (tmp_path / "b" / "drive.mp4").write_bytes(b"")
    (tmp_path / "calib.yaml").write_text("width: 10\n")
    for r in ("a", "b"):
        (tmp_path / r / "poses.csv").write_text("timestamp,x,y,yaw\n0,0,0,0\n")
    return tmp_path


def test_a_csv_manifest_gives_one_row_per_recording_with_absolute_paths(recordings):
    path = recordings / "m.csv"
    path.write_text("name,images,video,calibration,ego_poses,fps,start_time\n"
                    "first,a/images,,calib.yaml,a/poses.csv,10,\n"
                    ",,b/drive.mp4,calib.yaml,b/poses.csv,,12.5\n")
    first, second = read_manifest(path)
    assert (first.name, first.images, first.video, first.fps, first.start_time, first.row) == (
        "first", recordings / "a" / "images", None, 10.0, None, 1)
    assert (second.name, second.video, second.calibration, second.ego_poses, second.start_time, second.row) == (
        "drive", recordings / "b" / "drive.mp4", recordings / "calib.yaml", recordings / "b" / "poses.csv", 12.5, 2)


def test_a_yaml_manifest_reads_as_the_csv_one(recordings):
    csv_path, yaml_path = recordings / "m.csv", recordings / "m.yaml"
    csv_path.write_text("images,calibration,ego_poses\na/images,calib.yaml,a/poses.csv\n")
    yaml_path.write_text("recordings:\n  - {images: a/images, calibration: calib.yaml, ego_poses: a/poses.csv}\n")
    assert read_manifest(csv_path) == read_manifest(yaml_path)
    assert read_manifest(csv_path)[0].name == "images"


ROW = "a/images,,calib.yaml,a/poses.csv"


@pytest.mark.parametrize("text, message", [
    (f"images,video,calibration,ego_poses\n{ROW}\nmissing/images,,calib.yaml,a/poses.csv\n",
     "row 2: field 'images': folder {root}/missing/images not found"),
    ("images,video,calibration,ego_poses\na/images,,nowhere.yaml,a/poses.csv\n",
     "row 1: field 'calibration': file {root}/nowhere.yaml not found"),
    ("images,video,calibration,ego_poses\na/images,,calib.yaml,\n", "row 1: field 'ego_poses' is missing"),
    ("images,video,calibration,ego_poses\na/images,b/drive.mp4,calib.yaml,a/poses.csv\n",
     "row 1: give exactly one of the fields 'images'"),
    ("images,video,calibration,ego_poses\n,,calib.yaml,a/poses.csv\n", "row 1: give exactly one of the fields"),
    (f"images,video,calibration,ego_poses,fps\n{ROW},fast\n", "row 1: field 'fps' must be a number, got 'fast'"),
    (f"images,video,calibration,ego_poses,fps\n{ROW},-5\n", "row 1: field 'fps' must be a finite number > 0"),
    (f"images,video,calibration,ego_poses,fps\n{ROW},nan\n", "row 1: field 'fps' must be a finite number > 0"),
    (f"images,video,calibration,egoposes\n{ROW}\n", "header: unknown field\\(s\\) 'egoposes'; fields: name"),
    (f"images,video,calibration,ego_poses\n{ROW},extra\n", "row 1 has more cells than the header's 4 fields"),
    (f"name,images,video,calibration,ego_poses\nx,{ROW}\nx,{ROW}\n", "row 2: name 'x' is also row 1's"),
    (f"name,images,video,calibration,ego_poses\n../up,{ROW}\n", "row 1: field 'name' must be usable as a folder"),
    ("images,video,calibration,ego_poses\n", "the manifest lists no recording"),
])
def test_a_bad_csv_row_names_the_manifest_row_and_field(recordings, text, message):
    path = recordings / "m.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=f"^{path}: " + message.format(root=recordings)):
        read_manifest(path)


@pytest.mark.parametrize("name, text, message", [
    ("m.yaml", "recordings: {images: a}\n", "a YAML manifest must be a list of recordings"),
    ("m.yaml", "- [1, 2]\n", "a YAML manifest must be a list of recordings"),
    ("m.yaml", "- {images: a/images, calibraton: calib.yaml}\n", "row 1: unknown field\\(s\\) 'calibraton'"),
    ("m.yaml", "- {images: [unclosed\n", "not valid YAML"),
    ("m.json", "[]", "a manifest must be a .csv or .yaml file"),
    ("gone.csv", None, "cannot read the manifest"),
])
def test_a_bad_manifest_file_is_one_clear_error(recordings, name, text, message):
    path = recordings / name
    if text is not None:
        path.write_text(text)
    with pytest.raises(InputError, match=f"^{path}: {message}"):
        read_manifest(path)


@pytest.mark.parametrize("name, message", [
    ("summary.json", r"row 1: field 'name' 'summary\.json' is the name of a file the run writes in the output folder"),
    (".pedenv-output", r"row 1: field 'name' '\.pedenv-output' is the name of a file the run writes"),
    ("a" * 256, r"row 1: field 'name' must be usable as a folder name \(no / or \\, at most 255 bytes\)"),
])
def test_names_the_run_cannot_use_are_refused_before_it_starts(recordings, name, message):
    """Issue 19: a recording named summary.json ended in a traceback and no summary; 256 bytes in a traceback."""
    path = recordings / "m.csv"
    path.write_text(f"name,images,calibration,ego_poses\n{name},a/images,calib.yaml,a/poses.csv\n")
    with pytest.raises(InputError, match=r"m\.csv: " + message):
        read_manifest(path)


def test_a_path_field_over_255_bytes_is_one_error(recordings):
    path = recordings / "m.csv"
    path.write_text(f"images,calibration,ego_poses\n{'b' * 300}/images,calib.yaml,a/poses.csv\n")
    with pytest.raises(InputError, match=r"m\.csv: row 1: field 'images': .* is 300 bytes long; file systems take"):
        read_manifest(path)
