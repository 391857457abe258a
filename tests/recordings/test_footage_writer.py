"""KITTI tracking and MOT17 sequences written as ``pedenv run`` recordings, read back by
:mod:`pedenv.recordings.footage`, and ``pedenv run --detection far`` over them (real consecutive frames)."""

import json

import numpy as np
import pytest

from pedenv.boxes import iou_matrix
from pedenv.config import Config
from pedenv.datasets import kitti_files as kitti
from pedenv.datasets.kitti import KittiTrackingDataset
from pedenv.errors import InputError
from pedenv.localization import configure
from pedenv.outputs.jsonl import read_environment
from pedenv.recordings.footage import load_recording
from pedenv.recordings.footage_writer import write_kitti_recording, write_mot17_recording

from cli_in_process import pedenv
from shared_paths import REAL_SAMPLES

KITTI = REAL_SAMPLES / "kitti" / "tracking_mini"
MOT17 = REAL_SAMPLES / "mot17"


def _load(out):
    return load_recording(calibration=out / "calibration.yaml", ego_poses=out / "ego_poses.csv", images=out / "images")


def test_a_kitti_recording_reads_back_as_the_evaluate_adapter_sees_the_sequence(tmp_path):
    out = write_kitti_recording(KITTI / "training", "0016", tmp_path / "rec")
    frames = [(f.timestamp, f.camera, f.ego, f.image.shape) for f in _load(out).frames()]
    reference = list(KittiTrackingDataset(KITTI).frames("0016"))
    assert [t for t, *_ in frames] == pytest.approx([0.2, 0.7, 1.2])
    for (t, camera, ego, shape), ref in zip(frames, reference):
        assert t == pytest.approx(ref.timestamp)
        np.testing.assert_allclose(camera.intrinsics, ref.camera.intrinsics)
        np.testing.assert_allclose(camera.cam_to_vehicle, ref.camera.cam_to_vehicle, atol=1e-12)
        assert shape == (370, 1224, 3)
        np.testing.assert_allclose(ego.translation, ref.ego.translation, atol=1e-5)
        np.testing.assert_allclose(ego.rotation, ref.ego.rotation, atol=1e-6)
    with pytest.raises(InputError, match="not empty"):
        write_kitti_recording(KITTI / "training", "0016", tmp_path / "rec")


def test_a_mot17_recording_has_a_labelled_guessed_camera_and_a_standing_ego(tmp_path):
    out = write_mot17_recording(MOT17 / "MOT17-05-FRCNN", tmp_path / "rec")
    assert "GUESSED camera" in (out / "calibration.yaml").read_text()
    rec = _load(out)
    frames = list(rec.frames())
    assert len(frames) == 6 and frames[0].image.shape == (480, 640, 3)
    assert [f.timestamp for f in frames] == pytest.approx([n / 14.0 for n in range(6)])
    np.testing.assert_allclose(rec.camera.intrinsics, [[640, 0, 320], [0, 640, 240], [0, 0, 1]])
    assert frames[-1].ego.translation.tolist() == [0.0, 0.0, 0.0]
    with pytest.raises(InputError, match="camera_height_m"):
        write_mot17_recording(MOT17 / "MOT17-05-FRCNN", tmp_path / "other", camera_height_m=0.0)


def test_a_guessed_downward_pitch_makes_far_tile_the_whole_image(tmp_path):
    from pedenv.detection.config import DetectionConfig
    from pedenv.detection.geometry import CameraGeometry, far_band

    far = DetectionConfig.named("far")
    level = next(_load(write_mot17_recording(MOT17 / "MOT17-04-FRCNN", tmp_path / "level")).frames())
    down = next(_load(write_mot17_recording(MOT17 / "MOT17-04-FRCNN", tmp_path / "down", pitch_down_deg=30)).frames())
    band = far_band(CameraGeometry.from_frame(level), 1920, 1080, far)
    assert band is not None and band.top < 540 < band.bottom  # a level camera: the band holds the horizon
    assert far_band(CameraGeometry.from_frame(down), 1920, 1080, far) is None
    forward = down.camera.cam_to_vehicle[:3, 2]
    assert forward[2] == pytest.approx(-0.5)  # the optical axis points 30 deg below the horizon


def _ids_and_duplicates(environment, gt):
    """Per frame: ground-truth id -> reported track id (one-to-one, IoU >= 0.5); pairs reported twice."""
    from scipy.optimize import linear_sum_assignment

    found, duplicates = [], 0
    for line, (ids, boxes) in zip(read_environment(environment), gt):
        pboxes = np.array([p["box"] for p in line["pedestrians"]], float).reshape(-1, 4)
        tids = [p["track_id"] for p in line["pedestrians"]]
        iou = iou_matrix(boxes, pboxes)
        rows, cols = linear_sum_assignment(-iou)
        found.append({int(ids[r]): tids[c] for r, c in zip(rows, cols) if iou[r, c] >= 0.5})
        duplicates += int((np.triu(iou_matrix(pboxes, pboxes), 1) > 0.5).sum())
    return found, duplicates


@pytest.mark.slow
@pytest.mark.onnx_model
def test_pedenv_run_far_on_kitti_0016_keeps_ids_and_reports_nobody_twice(tmp_path, monkeypatch, capsys):
    rec = write_kitti_recording(KITTI / "training", "0016", tmp_path / "rec")
    configure(Config(), "fused").save(tmp_path / "fused.json")
    code, out, err = pedenv(monkeypatch, capsys, "run", "--calibration", rec / "calibration.yaml",
                            "--ego-poses", rec / "ego_poses.csv", "--images", rec / "images",
                            "--output", tmp_path / "run", "--detection", "far", "--config", tmp_path / "fused.json")
    assert code == 0, err
    seq = kitti.read_tracking_sequence(KITTI / "training", "0016")
    gt = [(lab.track_id, lab.boxes) for lab in (seq.labels.in_frame(f).of_type("Pedestrian") for f in seq.frames)]
    found, duplicates = _ids_and_duplicates(tmp_path / "run" / "environment.jsonl", gt)
    assert duplicates == 0
    # measured: 20 of the 24 boxes matched, 1 id switch (walker 22 in frame 12); walkers 5 and 6,
    # side by side, keep theirs
    assert sum(len(f) for f in found) >= 19
    switches = sum(found[k][i] != found[k - 1][i] for k in (1, 2) for i in found[k] if i in found[k - 1])
    assert switches <= 1
    assert found[0][5] == found[1][5] == found[2][5] and found[0][6] == found[1][6] == found[2][6]
    run = json.loads((tmp_path / "run" / "run.json").read_text())
    assert run["pose_backend"]["detection"]["mode"] == "far" and run["pose_backend"]["redetect"]["enabled"]


@pytest.mark.slow
@pytest.mark.onnx_model
def test_pedenv_run_far_on_mot17_05_keeps_ids_and_reports_nobody_twice(tmp_path, monkeypatch, capsys):
    matched, switches, duplicates = _run_mot17("MOT17-05-FRCNN", tmp_path, monkeypatch, capsys)
    assert duplicates == 0
    # measured (guessed camera, default config): 20 of the 45 boxes matched one to one, no id switch
    assert switches == 0
    assert matched >= 19


@pytest.mark.slow
@pytest.mark.onnx_model
def test_a_guessed_camera_does_not_split_the_fused_tracks_on_mot17_04(tmp_path, monkeypatch, capsys):
    """MOT17-04 looks down from high up; its camera is guessed (30 deg down, 1.5 m up). The
    fused default's ground gate would split nearly every track (210 id switches in 8 frames
    before the camera check, pedenv.tracking.recall.CAMERA_CHECK); the image contradicts that
    camera, so the boxes decide."""
    matched, switches, duplicates = _run_mot17("MOT17-04-FRCNN", tmp_path, monkeypatch, capsys, pitch_down_deg=30)
    assert duplicates == 0
    # measured: 240 of the boxes matched one to one, no id switch (the paper's tracker: 0 too)
    assert matched >= 228 and switches <= 2


def _run_mot17(name: str, tmp_path, monkeypatch, capsys, **camera) -> tuple[int, int, int]:
    """``pedenv run --detection far`` (default config) on a MOT17 sample written as a recording
    with a guessed ``camera``: (boxes matched one to one, id switches, people reported twice)."""
    from pedenv.datasets import mot17

    rec = write_mot17_recording(MOT17 / name, tmp_path / "rec", **camera)
    code, out, err = pedenv(monkeypatch, capsys, "run", "--calibration", rec / "calibration.yaml",
                            "--ego-poses", rec / "ego_poses.csv", "--images", rec / "images",
                            "--output", tmp_path / "run", "--detection", "far")
    assert code == 0, err
    seq = mot17.read_sequence(MOT17 / name)
    gt = [(rows.ids, rows.boxes) for rows in (seq.pedestrians.in_frame(f) for f in seq.frames)]
    found, duplicates = _ids_and_duplicates(tmp_path / "run" / "environment.jsonl", gt)
    switches = sum(found[k][i] != found[k - 1][i] for k in range(1, len(found)) for i in found[k] if i in found[k - 1])
    return sum(len(f) for f in found), switches, duplicates
