"""A camera declared --static whose view moves is refused before anything runs; real fixed cameras are not."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.apps.options import OutputOptions, RecordingSource
from pedenv.apps.run import run_recording
from pedenv.errors import InputError
from pedenv.odometry.static_check import MOVED_PX, check_static
from pedenv.records import Detections, Frame

from shared_paths import REAL_SAMPLES

KITTI_RAW = REAL_SAMPLES / "kitti/raw_2011_09_26_drive_0002/2011_09_26_drive_0002_sync/image_02/data"
MOT17 = REAL_SAMPLES / "mot17"


class NoPeople:
    name = "no-people"

    def __call__(self, frame: Frame, tracks=None) -> Detections:  # noqa: ARG002 - the PoseBackend protocol
        return Detections.empty()


@pytest.mark.parametrize("sequence", ["MOT17-02-FRCNN", "MOT17-04-FRCNN", "MOT17-09-FRCNN"])
def test_real_fixed_cameras_pass(sequence):
    flows = check_static(images=MOT17 / sequence / "img1")
    assert flows and max(flow for _, flow in flows) < 0.5 < MOVED_PX  # measured at most 0.47 px


@pytest.mark.parametrize("sequence", ["MOT17-05-FRCNN", "MOT17-10-FRCNN", "MOT17-11-FRCNN", "MOT17-13-FRCNN"])
def test_real_moving_cameras_are_refused(sequence):
    with pytest.raises(InputError, match=rf"{sequence}/img1: declared --static, but the camera moves: its background "
                                         r"moved a median \d+\.\d px from frame \d to frame \d"):
        check_static(images=MOT17 / sequence / "img1")


def test_a_driving_car_declared_static_stops_the_run_before_anything_runs(tmp_path):
    # KITTI raw 0002 at 9 m/s as an image folder, --static and no calibration: refused before the warm-up
    with pytest.raises(InputError, match=r"declared --static, but the camera moves: its background moved a median "
                                         r"\d+\.\d px from frame \d to frame \d+ \(5 of 5 frame pairs moved 2 px or "
                                         r"more\); give the camera's ego poses \(--ego-poses\), or drop --static"):
        run_recording(RecordingSource(images=KITTI_RAW, static=True, fps=10.0), OutputOptions(tmp_path / "out"),
                      backend=NoPeople())
    assert not (tmp_path / "out").exists()


def test_a_refused_output_folder_is_refused_before_the_odometry(tmp_path, monkeypatch):
    def no_odometry(*_, **__):
        raise AssertionError("the odometry ran before the output folder was checked")

    monkeypatch.setattr("pedenv.odometry.stream.OdometryStream.add", no_odometry)
    calib = tmp_path / "calib.yaml"
    calib.write_text("width: 1242\nheight: 375\nfx: 721.5\nfy: 721.5\ncx: 609.6\ncy: 172.9\n"
                     "cam_to_vehicle: {rotation: [0.5, -0.5, 0.5, -0.5], translation: [0, 0, 1.65]}\n")
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="output folder .*out is not empty; pass --overwrite"):
        run_recording(RecordingSource(images=KITTI_RAW, calibration=calib, fps=10.0), OutputOptions(out),
                      backend=NoPeople())
    assert np.array_equal(sorted(p.name for p in out.iterdir()), ["notes.txt"])
