"""Issue 32: ``pedenv run`` never loses a user's data. Each case compares the input's (or the
earlier run's) bytes before and after; tiny synthetic recordings, a pose backend that finds
nobody (no network), and a full disk simulated by the free space the guard reads."""

from __future__ import annotations

import errno
import hashlib
import json
import socket
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest

import pedenv.apps.output_safety as safety
from pedenv.apps.options import OutputOptions
from pedenv.apps.options import RecordingSource as Source
from pedenv.apps.run import run_recording
from pedenv.errors import InputError
from pedenv.outputs.jsonl import EnvironmentWriter, read_environment
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.records import Detections
from pedenv.video_files import VideoOut

from cli_in_process import pedenv


class Nobody:
    """A pose backend that finds no one (the outputs are what is tested, not the network)."""

    name = "nobody"

    def __call__(self, frame, *_tracks):  # noqa: ARG002 - the backend protocol (tracks: where a pipeline passes them)
        return Detections.empty()


def recording(folder: Path, frames: int = 5, step_s: float = 0.1, size: tuple[int, int] = (64, 48)) -> dict:
    """A recording of ``frames`` grey PNGs ``step_s`` apart, its calibration and ego poses."""
    w, h = size
    (folder / "images").mkdir(parents=True)
    for i in range(frames):
        cv2.imwrite(str(folder / "images" / f"f{i:03d}.png"), np.full((h, w, 3), 40 + i, np.uint8))
    (folder / "images" / "timestamps.csv").write_text(
        "filename,timestamp\n" + "".join(f"f{i:03d}.png,{100 + step_s * i!r}\n" for i in range(frames)))
    (folder / "calib.yaml").write_text(
        f"width: {w}\nheight: {h}\nfx: 50.0\nfy: 50.0\ncx: {w / 2}\ncy: {h / 2}\ncam_to_vehicle:\n"
        "  rotation: [0.5, -0.5, 0.5, -0.5]\n  translation: [1.0, 0.0, 1.5]\n")
    (folder / "poses.csv").write_text("timestamp,x,y,yaw\n99.0,0,0,0\n1000.0,10,0,0\n")
    return {"images": folder / "images", "calibration": folder / "calib.yaml", "ego_poses": folder / "poses.csv"}


def digest(*paths: Path) -> dict[str, str]:
    """sha256 of every file under ``paths`` (files or folders), by path."""
    files = [f for p in paths for f in ([p] if p.is_file() else sorted(p.rglob("*"))) if f.is_file()]
    return {str(f): hashlib.sha256(f.read_bytes()).hexdigest() for f in files}


def run(rec: dict, out: Path, **options) -> dict:
    extra = options.pop("extra", None)
    return run_recording(Source(**rec), OutputOptions(out, extra=extra, **options), backend=Nobody())


def frames_in_video(path: Path) -> int:
    cap = cv2.VideoCapture(str(path))
    n = 0
    while cap.read()[0]:
        n += 1
    cap.release()
    return n


# item 1 and 11: an output on an input, two outputs on one file ------------------------------------


@pytest.mark.parametrize("flag", ["ros", "mcap"])
def test_an_output_on_the_input_bag_is_refused_with_overwrite(tmp_path, flag):
    bag = tmp_path / "in.mcap"
    bag.write_bytes(b"\x89MCAP0\r\n" + bytes(range(256)) * 64)
    before = digest(bag)
    with pytest.raises(InputError, match=r"^--(ros-out|mcap) .*in\.mcap is the input --bag"):
        run_recording(Source(bag=bag), OutputOptions(tmp_path / "o", overwrite=True,
                                                     extra=ExtraOutputs(**{flag: bag}, overwrite=True)),
                      backend=Nobody())
    assert digest(bag) == before and not (tmp_path / "o").exists()


def test_an_output_inside_a_rosbag2_folder_is_refused(tmp_path):
    bag = tmp_path / "drive"
    bag.mkdir()
    (bag / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    (bag / "drive_0.mcap").write_bytes(b"recorded")
    before = digest(bag)
    with pytest.raises(InputError, match="lies inside the input --bag"):
        run_recording(Source(bag=bag), OutputOptions(tmp_path / "o", extra=ExtraOutputs(
            ros=bag / "drive_0.mcap", overwrite=True)), backend=Nobody())
    assert digest(bag) == before


def test_an_output_linked_to_an_input_image_is_refused(tmp_path):
    rec = recording(tmp_path / "rec", frames=2)
    (tmp_path / "elsewhere").mkdir()
    link = tmp_path / "elsewhere" / "same.mcap"
    link.symlink_to(rec["images"] / "f000.png")
    before = digest(tmp_path / "rec")
    with pytest.raises(InputError, match="f000.png lies inside the input --images"):
        run(rec, tmp_path / "o", overwrite=True, extra=ExtraOutputs(mcap=link, overwrite=True))
    assert digest(tmp_path / "rec") == before


def test_the_output_folder_inside_the_images_is_refused(tmp_path):
    rec = recording(tmp_path / "rec", frames=2)
    before = digest(tmp_path / "rec")
    with pytest.raises(InputError, match="^--output .*images/out lies inside the input --images"):
        run(rec, rec["images"] / "out")
    assert digest(tmp_path / "rec") == before


def test_ros_out_and_mcap_on_one_file_are_refused(tmp_path):
    rec = recording(tmp_path / "rec", frames=2)
    with pytest.raises(InputError, match="^--mcap and --ros-out name one file"):
        run(rec, tmp_path / "o", extra=ExtraOutputs(mcap=tmp_path / "x.mcap", ros=tmp_path / "x.mcap"))
    assert not (tmp_path / "o").exists() and not (tmp_path / "x.mcap").exists()


def test_ros_out_leaves_a_users_partial_folder_alone(tmp_path):
    """``--ros-out y.mcap`` deleted an existing ``y.mcap.partial/`` folder without --overwrite."""
    rec = recording(tmp_path / "rec", frames=2)
    mine = tmp_path / "y.mcap.partial"
    mine.mkdir()
    (mine / "notes.txt").write_text("mine")
    run(rec, tmp_path / "o", extra=ExtraOutputs(ros=tmp_path / "y.mcap"))
    assert (mine / "notes.txt").read_text() == "mine"
    assert (tmp_path / "y.mcap").read_bytes()[:8] == b"\x89MCAP0\r\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["o", "rec", "y.mcap", "y.mcap.partial"]


# item 2 and 5: --overwrite ------------------------------------------------------------------------


def test_overwrite_refuses_an_output_folder_holding_the_inputs(tmp_path):
    out = tmp_path / "o"
    run(recording(tmp_path / "first", frames=2), out)
    rec = recording(out / "rec", frames=2)  # the user copied the recording into the earlier run's folder
    before = digest(out)
    with pytest.raises(InputError, match="^--output .*o holds the input --images"):
        run(rec, out, overwrite=True)
    assert digest(out) == before


def test_overwrite_keeps_the_earlier_run_when_an_image_is_cut(tmp_path):
    """The header check passed, the earlier run was emptied, the new run wrote 0 frames."""
    rec = recording(tmp_path / "rec", frames=4)
    out = tmp_path / "o"
    run(rec, out)
    before = digest(out)
    cut = rec["images"] / "f002.png"
    cut.write_bytes(cut.read_bytes()[:60])  # the header holds, the pixels are gone
    with warnings.catch_warnings(record=True) as caught, pytest.raises(InputError, match="f002.png"):
        warnings.simplefilter("always")
        run(rec, out, overwrite=True)
    assert digest(out) == before
    beside = [p for p in tmp_path.iterdir() if p.name.startswith("o.pedenv-new-")]
    assert len(beside) == 1 and len(read_environment(beside[0] / "environment.jsonl")) == 2
    assert any("the earlier run in" in str(w.message) and "2 frames" in str(w.message) for w in caught)


def test_overwrite_swaps_the_new_run_in_and_refuses_files_pedenv_did_not_write(tmp_path):
    out = tmp_path / "o"
    run(recording(tmp_path / "a", frames=4), out)
    summary = run(recording(tmp_path / "b", frames=2), out, overwrite=True)
    assert summary["frames_done"] == 2 and len(read_environment(out / "environment.jsonl")) == 2
    assert sorted(p.name for p in (out / "overlays").iterdir()) == ["000000.jpg", "000001.jpg"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "b", "o"]  # nothing left beside it
    (out / "notes.txt").write_text("mine")
    before = digest(out)
    with pytest.raises(InputError, match="notes.txt, which pedenv did not write"):
        run(recording(tmp_path / "c", frames=2), out, overwrite=True)
    assert digest(out) == before


# item 4: a full disk ------------------------------------------------------------------------------


def test_a_full_disk_stops_at_a_frame_with_every_output_valid(tmp_path, monkeypatch):
    """The free space the guard reads drops to nothing after 3 frames: one line naming the folder,
    the JSON Lines whole, run.json written and agreeing, the bird's-eye video finished, the
    Parquet and MCAP files closed, the room kept back released."""
    rec = recording(tmp_path / "rec", frames=8)
    real = safety._free
    calls = {"n": 0}

    def free(folder):
        calls["n"] += 1
        return real(folder) if calls["n"] <= 9 else 1000  # 3 calls to start, 2 a frame: frames 0-2 fit

    monkeypatch.setattr(safety, "_free", free)
    out = tmp_path / "o"
    extra = ExtraOutputs(parquet=out / "environment.parquet", mcap=tmp_path / "m" / "f.mcap")
    with pytest.raises(InputError, match=r"o: the disk is full .* stopped after 3 frames"):
        run(rec, out, extra=extra)
    summary = json.loads((out / "run.json").read_text())
    assert summary["frames_done"] == 3 == len(read_environment(out / "environment.jsonl"))
    assert frames_in_video(out / "birds_eye.mp4") == 3 and summary["bytes_written"] > 0
    import pyarrow.parquet as pq
    from mcap.reader import make_reader

    assert pq.read_table(out / "environment.parquet").num_rows == 0  # nobody found, but the file is whole
    with (tmp_path / "m" / "f.mcap").open("rb") as f:
        assert make_reader(f).get_summary() is not None
    assert not (out / ".pedenv-reserve").exists()


def test_a_write_that_fails_cuts_the_json_lines_back_to_a_whole_line(tmp_path):
    path = tmp_path / "environment.jsonl"
    with EnvironmentWriter(path) as writer:
        writer.write_line('{"frame":0}')
        real = writer._file

        class Full:
            def write(self, data):
                real.write(bytes(data[:5]))
                raise OSError(errno.ENOSPC, "No space left on device")

            def truncate(self, size):
                return real.truncate(size)

        writer._file = Full()
        with pytest.raises(InputError, match="environment.jsonl: cannot be written: No space left on device"):
            writer.write_line('{"frame":1}')
        writer._file = real
    assert path.read_text() == '{"frame":0}\n' and writer.lines == 1


def test_a_run_that_will_not_fit_is_warned_about_early(tmp_path, monkeypatch):
    """A disk of 1 MB on which each frame takes 100 kB: warned after 3 frames, stopped after 5 (two
    frames and the writers' buffers, 320 KiB, must fit)."""
    rec = recording(tmp_path / "rec", frames=12)
    overlays = tmp_path / "o" / "overlays"
    monkeypatch.setattr(safety, "_free", lambda _: 1_000_000 - 100_000 * len(list(overlays.glob("*.jpg"))))
    with warnings.catch_warnings(record=True) as caught, \
            pytest.raises(InputError, match="the disk is full .* stopped after 5 frames"):
        warnings.simplefilter("always")
        run(rec, tmp_path / "o")
    assert [str(w.message).split(": ", 1)[1] for w in caught if "frames left" in str(w.message)] == [
        "at 0.10 MB per frame the 9 frames left need 1 MB and 1 MB are free: the run will stop when the disk is "
        "full (--video-out writes the overlays as one small video)"]
    assert len(read_environment(tmp_path / "o" / "environment.jsonl")) == 5


# bounded by default, item 13 ----------------------------------------------------------------------


def test_run_json_says_how_much_was_written_and_the_overlays_are_jpeg(tmp_path):
    summary = run(recording(tmp_path / "rec", frames=3), tmp_path / "o")
    out = tmp_path / "o"
    on_disk = sum(f.stat().st_size for f in out.rglob("*") if f.is_file() and f.name != "run.json")
    assert summary["bytes_written"] == on_disk
    assert [p.name for p in sorted((out / "overlays").iterdir())] == ["000000.jpg", "000001.jpg", "000002.jpg"]
    assert cv2.imread(str(out / "overlays" / "000002.jpg")).shape == (48, 64, 3)


def test_frames_microseconds_apart_do_not_stop_the_run(tmp_path):
    """The first frames 10 µs apart asked the encoder for 100000 fps: the run stopped, blaming a picture,
    with one more line in environment.jsonl than run.json said."""
    summary = run(recording(tmp_path / "rec", frames=4, step_s=1e-5), tmp_path / "o", video_out=True)
    assert summary["frames_done"] == 4 == len(read_environment(tmp_path / "o" / "environment.jsonl"))
    assert frames_in_video(tmp_path / "o" / "birds_eye.mp4") == 4
    assert frames_in_video(tmp_path / "o" / "overlay.mp4") == 4


@pytest.mark.parametrize("fps", [1e300, 1e5, 1e-9, float("inf")])
def test_a_video_at_a_rate_the_encoder_refuses_is_clamped(tmp_path, fps):
    video = VideoOut(tmp_path / "v.mp4", fps, (32, 32))
    video.write(np.zeros((32, 32, 3), np.uint8))
    video.release()
    assert frames_in_video(tmp_path / "v.mp4") == 1


# item 3: --live -----------------------------------------------------------------------------------


def test_live_ends_with_an_idle_client_and_says_its_port(tmp_path, monkeypatch):
    """A connection left half-open made the server's stop() wait for ever: no run.json, unreadable mp4s."""
    import pedenv.outputs.live_view as live

    monkeypatch.setattr(live, "STOP_TIMEOUT_S", 0.5)
    rec = recording(tmp_path / "rec", frames=3)
    clients = []

    class Connecting(Nobody):
        def __call__(self, frame, *tracks):
            if not clients:  # the server is up once frames run: a client that never finishes its handshake
                import gc

                port = next(o.port for o in gc.get_objects() if isinstance(o, live.LiveViewer))
                clients.append(socket.create_connection(("127.0.0.1", port)))
                clients[0].sendall(b"GET / HTTP/1.1\r\n")
            return super().__call__(frame, *tracks)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        summary = run_recording(Source(**rec), OutputOptions(tmp_path / "o", extra=ExtraOutputs(live=0)),
                                backend=Connecting())
    clients[0].close()
    assert summary["live"].startswith("ws://127.0.0.1:") and summary["frames_done"] == 3
    assert json.loads((tmp_path / "o" / "run.json").read_text())["live"] == summary["live"]
    assert frames_in_video(tmp_path / "o" / "birds_eye.mp4") == 3
    assert any(f"a client of {summary['live']} holds the server" in str(w.message) for w in caught)


def test_live_port_zero_is_chosen_and_printed_before_the_run(tmp_path, monkeypatch, capsys):
    import pedenv.apps.run as run_module

    monkeypatch.setattr(run_module, "_make_backend", lambda *_: Nobody())
    rec = recording(tmp_path / "rec", frames=2)
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", rec["images"], "--calibration", rec["calibration"],
                          "--ego-poses", rec["ego_poses"], "--output", tmp_path / "o", "--live", "--live-port", "0")
    address = json.loads((tmp_path / "o" / "run.json").read_text())["live"]
    assert code == 0 and err.splitlines()[0] == f"live: {address} (connect Foxglove to it)"
    assert int(address.rsplit(":", 1)[1]) > 0


# item 15 ------------------------------------------------------------------------------------------


def test_a_bad_live_port_is_one_line(monkeypatch, capsys, tmp_path):
    code, _, err = pedenv(monkeypatch, capsys, "run", "--images", tmp_path, "--calibration", tmp_path / "c.yaml",
                          "--ego-poses", tmp_path / "p.csv", "--output", tmp_path / "o", "--live", "--live-port",
                          "abc")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("error: pedenv run: Invalid value for '--live-port'")


def test_detect_on_a_fifo_is_one_line(monkeypatch, capsys, tmp_path):
    import os

    fifo = tmp_path / "camera.png"
    os.mkfifo(fifo)
    code, _, err = pedenv(monkeypatch, capsys, "detect", fifo, "--output", tmp_path / "o")
    assert code == 2 and err.strip() == f"error: image {fifo} is not a regular file (a FIFO, a device or a folder); " \
                                        "give a file"


def test_a_sink_that_cannot_be_finished_is_one_line_and_the_others_close(tmp_path):
    from pedenv.outputs.sinks import Sinks

    closed = []

    class Sink:
        def __init__(self, name, fail):
            self.path, self.fail = tmp_path / name, fail

        def write(self, state, frame):  # noqa: ARG002 - the sink protocol
            raise OSError(errno.ENOSPC, "No space left on device")

        def close(self):
            closed.append(self.path.name)
            if self.fail:
                raise OSError(errno.ENOSPC, "No space left on device")

    sinks = Sinks([Sink("a.mcap", True), Sink("b.mp4", False)])
    with pytest.raises(InputError, match=r"a.mcap: cannot be written: No space left on device"):
        sinks.write(None, None)
    with pytest.raises(InputError, match=r"a.mcap: cannot be finished: No space left on device"):
        sinks.close()
    assert closed == ["a.mcap", "b.mp4"]


# files outside the output folder: an earlier one replaced only when the run has finished ----------


def test_overwrite_keeps_earlier_files_outside_the_folder_when_the_run_stops(tmp_path):
    """``--rerun``/``--mcap``/``--ros-out`` files of an earlier run outside the output folder: a run that
    stops at a cut image (frame 2) leaves their bytes as they were, the new ones beside them named in
    a warning; a run that finishes renames them over the earlier ones and leaves nothing beside."""
    rec = recording(tmp_path / "rec", frames=4)
    side = tmp_path / "side"
    extra = ExtraOutputs(rerun=side / "r.rrd", mcap=side / "m.mcap", ros=side / "b.mcap", overwrite=True)
    run(rec, tmp_path / "o1", extra=extra)
    before = digest(side)
    assert sorted(Path(p).name for p in before) == ["b.mcap", "m.mcap", "r.rrd"]
    cut = rec["images"] / "f002.png"
    good = cut.read_bytes()
    cut.write_bytes(good[:60])  # the header holds, the pixels are gone
    with warnings.catch_warnings(record=True) as caught, pytest.raises(InputError, match="f002.png"):
        warnings.simplefilter("always")
        run(rec, tmp_path / "o2", overwrite=True, extra=extra)
    assert digest(side).items() >= before.items()  # the earlier files, byte for byte
    beside = sorted(p.name for p in side.iterdir() if p.name.startswith(safety.SIDE_PREFIX))
    assert sorted(n.rsplit("-", 1)[-1] for n in beside) == ["b.mcap", "m.mcap", "r.rrd"]
    kept = [str(w.message) for w in caught if "is kept as it was" in str(w.message)]
    assert len(kept) == 3 and all("2 frames" in k for k in kept)
    from mcap.reader import make_reader

    with next(side.glob(f"{safety.SIDE_PREFIX}*-m.mcap")).open("rb") as f:  # the stopped run's file is whole
        assert make_reader(f).get_summary() is not None
    for name in beside:
        (side / name).unlink()
    cut.write_bytes(good)
    inodes = {p.name: p.stat().st_ino for p in side.iterdir()}
    summary = run(rec, tmp_path / "o3", overwrite=True, extra=extra)
    assert sorted(p.name for p in side.iterdir()) == ["b.mcap", "m.mcap", "r.rrd"]  # renamed over, none beside
    assert all(p.stat().st_ino != inodes[p.name] for p in side.iterdir())
    assert {str(side / n) for n in ["b.mcap", "m.mcap", "r.rrd"]} <= set(summary["files"])


def test_a_run_that_stops_before_its_first_frame_leaves_nothing_beside_an_earlier_file(tmp_path):
    rec = recording(tmp_path / "rec", frames=3)
    side = tmp_path / "side"
    side.mkdir()
    (side / "m.mcap").write_bytes(b"an earlier recording")
    (rec["images"] / "f000.png").write_bytes(b"\x89PNG\r\n\x1a\n")  # cut in frame 0
    with pytest.raises(InputError, match="f000.png"):
        run(rec, tmp_path / "o", overwrite=True, extra=ExtraOutputs(mcap=side / "m.mcap", overwrite=True))
    assert [p.name for p in side.iterdir()] == ["m.mcap"] and (side / "m.mcap").read_bytes() == b"an earlier recording"
