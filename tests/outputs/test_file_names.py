"""Issue 19: hostile file names and sizes. Names that are not UTF-8 (OpenCV segfaulted on them),
names over 255 bytes, images that announce more pixels than memory holds, --rerun/--mcap
targets, and per-frame outputs that must grow linearly with the stream."""

from __future__ import annotations

import os
import struct
import zlib

import cv2
import numpy as np
import pytest

from pedenv.errors import InputError
from pedenv.images import MAX_IMAGE_PIXELS, image_size, read_image_rgb, write_image
from pedenv.outputs.ego_path import EgoPath
from pedenv.outputs.output_dir import check_output_file, prepare_output_dir
from pedenv.paths import check_path, is_utf8
from pedenv.records import EgoPose
from pedenv.state import EnvironmentState, Pedestrians
from pedenv.video_files import VideoOut, video_capture
from pedenv.visualize.birds_eye_video import BirdsEyeVideo

NOT_UTF8 = os.fsdecode(b"x\xff")  # a name with the byte 0xff, as a file system may hold it


def _png_header(path, width: int, height: int) -> None:
    """A PNG file whose header announces ``width`` x ``height`` pixels (the pixel data is cut short)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + header + chunk(b"IDAT", zlib.compress(b"\0" * 1000)))


def test_images_and_videos_under_names_that_are_not_utf8(tmp_path):
    folder = tmp_path / NOT_UTF8
    assert not is_utf8(folder)
    image = np.zeros((48, 64, 3), np.uint8)
    image[10:20, 5:15] = (255, 0, 0)
    written = write_image(folder / f"{NOT_UTF8}.png", image)
    assert os.fsencode(written.name) == b"x\xff.png" and np.array_equal(read_image_rgb(written), image)
    video = VideoOut(folder / f"{NOT_UTF8}.mp4", 10.0, (64, 48))
    for _ in range(5):
        video.write(image[..., ::-1].copy())
    video.release()
    with video_capture(folder / f"{NOT_UTF8}.mp4") as cap:
        assert int(cap.get(cv2.CAP_PROP_FRAME_COUNT)) == 5 and int(cap.get(cv2.CAP_PROP_FRAME_WIDTH)) == 64
    assert sorted(os.fsencode(p.name) for p in folder.iterdir()) == [b"x\xff.mp4", b"x\xff.png"]


def test_the_pixel_limit_is_read_from_the_header_before_decoding(tmp_path, monkeypatch):
    from PIL import Image

    huge = tmp_path / "huge.png"
    _png_header(huge, 30000, 30000)  # 2.7 GB once decoded; 1 KB on disk
    # ultralytics switches Pillow's own limit off (Image.MAX_IMAGE_PIXELS = None) once imported:
    # both ways give one clear error
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", None)
    with pytest.raises(InputError, match=r"huge\.png: the image is 30000x30000 pixels, above the limit of 64 "):
        image_size(huge)
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 89_478_485)  # Pillow's default
    for read in (image_size, read_image_rgb):
        with pytest.raises(InputError, match=r"huge\.png: the image has 900000000 pixels, above the limit of 64 "
                                             r"megapixels \(pedenv\.images\.MAX_IMAGE_PIXELS\)"):
            read(huge)
    _png_header(huge, 9000, 8000)  # above our limit, below Pillow's own
    with pytest.raises(InputError, match=r"huge\.png: the image is 9000x8000 pixels, above the limit of 64 "):
        image_size(huge)
    _png_header(huge, 8000, 8000)
    assert MAX_IMAGE_PIXELS >= 8000 * 8000 and image_size(huge) == (8000, 8000)


LONG = "a" * 256


@pytest.mark.parametrize("path", [LONG, f"out/{LONG}/x", f"{'é' * 128}"])
def test_names_over_255_bytes_are_one_error(tmp_path, path):
    with pytest.raises(InputError, match=r"output folder .*: the name .* is 256 bytes long; file systems take at "
                                         r"most 255"):
        prepare_output_dir(tmp_path / path)
    check_path(tmp_path / ("a" * 255), "output folder")  # 255 is fine


@pytest.mark.parametrize("target, options, message", [
    ("poses.csv", {}, r"--rerun .*poses\.csv: the file name must end in \.rrd"),
    ("out/environment.jsonl", {}, r"--rerun .*environment\.jsonl: the file name must end in \.rrd"),
    ("adir.rrd", {}, r"--rerun .*adir\.rrd is a folder"),
    ("poses.csv/x.rrd", {}, r"--rerun .*x\.rrd lies under .*poses\.csv, which is a file"),
    ("old.rrd", {}, r"--rerun .*old\.rrd exists; pass --overwrite to replace it"),
    ("run.rrd", {}, r"--rerun .*run-scene-a\.rrd exists; pass --overwrite"),  # an earlier run's per-scene file
    (f"{NOT_UTF8}.rrd", {}, r"the name is not UTF-8 text, which the rerun writer needs"),
    ("/proc/pedenv-test/x.rrd", {}, r"--rerun /proc/pedenv-test/x\.rrd cannot be written"),
    (f"{LONG}.rrd", {}, r"is 260 bytes long"),
    ("old.rrd", {"overwrite": True}, None),
    ("new/sub/x.rrd", {}, None),
])
def test_rerun_and_mcap_targets_are_checked_before_the_run(tmp_path, target, options, message):
    (tmp_path / "poses.csv").write_text("timestamp,x,y,yaw\n0,0,0,0\n")
    (tmp_path / "old.rrd").write_text("an earlier recording")
    (tmp_path / "run-scene-a.rrd").write_text("an earlier recording")
    (tmp_path / "adir.rrd").mkdir()
    path = target if target.startswith("/") else tmp_path / target
    if message is None:
        assert check_output_file(path, "--rerun", ".rrd", **options) == path
    else:
        with pytest.raises(InputError, match=message):
            check_output_file(path, "--rerun", ".rrd", **options)
    assert (tmp_path / "poses.csv").read_text() == "timestamp,x,y,yaw\n0,0,0,0\n"
    assert (tmp_path / "old.rrd").read_text() == "an earlier recording"


def test_the_ego_path_is_logged_in_pieces():
    path = EgoPath(piece_points=4)
    pieces = [path.add([float(i), 0.0, 0.0]) for i in range(9)]
    assert [p for p, _ in pieces] == [0, 0, 0, 0, 1, 1, 1, 2, 2]
    assert pieces[3][1][:, 0].tolist() == [0, 1, 2, 3]
    assert pieces[4][1][:, 0].tolist() == [3, 4]  # the next piece starts where the last one ended
    assert max(len(points) for _, points in pieces) == 4


def _state(i: int, track_ids) -> EnvironmentState:
    n = len(track_ids)
    p = Pedestrians.empty()
    peds = Pedestrians(np.asarray(track_ids, np.int64), np.ones(n, np.int64), np.tile([[10.0, 0.0, 0.0]], (n, 1)),
                       np.zeros((n, 3)), np.tile(np.eye(2) * 0.1, (n, 1, 1)), np.zeros((n, 17, 2)),
                       np.ones((n, 17)), np.tile([0.0, 0.0, 10.0, 20.0], (n, 1)), np.zeros((n, 17, 3)),
                       np.full(n, 10.0), np.array(["ground"] * n, dtype=p.sources.dtype))
    return EnvironmentState(i, 0.1 * i, EgoPose.from_xy_yaw(0.5 * i, 0.0, 0.0), peds, scene="long")


def test_the_birds_eye_video_drops_the_trails_of_tracks_gone_long_ago(tmp_path):
    video = BirdsEyeVideo(tmp_path / "birds_eye.mp4", trail=30, size_px=200)
    for i in range(300):  # a new track every 5 frames, each seen for 10 frames: 60 ids in all
        video.write(_state(i, [k for k in range(i // 5 - 1, i // 5 + 1) if k >= 0]))
        assert video.trails_kept <= 8  # the ids of the last 30 frames, not every id ever seen
    video.close()
    assert video.frames_written == 300


@pytest.mark.slow
def test_the_rerun_file_grows_linearly(tmp_path):
    import rerun.dataframe as rrd

    from pedenv.outputs.rerun_log import RerunWriter
    from pedenv.records import Camera, Frame

    writer, sizes = RerunWriter(tmp_path / "long.rrd"), []
    camera = Camera.from_fov(64, 48, 60.0)
    for i in range(600):
        state = _state(i, [0, 1])
        writer.write(state, Frame(i, state.timestamp, camera, state.ego))
        if i % 200 == 199:
            sizes.append((tmp_path / "long.rrd").stat().st_size)
    writer.close()
    table = rrd.load_recording(tmp_path / "long.rrd").view(index="frame", contents="/**").select().read_all()
    pieces = sorted(c for c in table.column_names if c.startswith("/world/ego_trajectory/") and "LineStrip3D" in c)
    assert len(pieces) == 7  # 600 positions in pieces of 100 (each starting where the last ended)
    logged = [len(row[0]) for c in pieces for row in table.column(c).to_pylist() if row]
    assert max(logged) == 100  # a frame logs at most one piece, not the whole path (600 points at the end)
    growth = np.diff([0, *sizes])  # bytes per 200 frames: measured 8.28, 8.27, 8.27 MB (was 8.32, 8.48, 8.64)
    assert growth[2] < 1.02 * growth[0], growth
