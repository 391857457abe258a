"""``pedenv calibrate``'s library function on images of the built-in static scene, people from the detector model."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from scene_backend import SceneBackend

from pedenv.apps.options import RecordingSource
from pedenv.calibration.geometry import parameters_of
from pedenv.recordings.footage import load_calibration, load_intrinsics
from pedenv.records import Frame


@pytest.fixture(scope="module")
def plaza(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, tuple[Frame, ...]]:
    from pedenv.images import write_image
    from pedenv.synthetic.generator import generate_scenes

    frames = generate_scenes(0, ["static-plaza"])[0].frames
    folder = tmp_path_factory.mktemp("plaza") / "images"
    folder.mkdir()
    blank = np.full((900, 1600, 3), 90, np.uint8)
    for frame in frames:
        write_image(folder / f"{frame.index:06d}.jpg", blank)
    (folder / "timestamps.csv").write_text("filename,timestamp\n" + "".join(
        f"{f.index:06d}.jpg,{f.timestamp}\n" for f in frames))
    return folder, frames


def test_calibrate_writes_a_reusable_estimated_calibration(plaza: tuple[Path, tuple[Frame, ...]],
                                                           tmp_path: Path) -> None:
    from pedenv.apps.calibrate import calibrate

    folder, frames = plaza
    summary = calibrate(output=tmp_path / "cal", source=RecordingSource(images=folder, static=True),
                        backend=SceneBackend(frames))
    truth = parameters_of(frames[0].camera)
    assert summary["focal_px"] == pytest.approx(truth[0], rel=0.05)
    assert summary["height_m"] == pytest.approx(truth[1], rel=0.05)
    assert json.loads((tmp_path / "cal" / "calibration.json").read_text())["warmup_frames"] == 150
    assert (tmp_path / "cal" / "calibration.png").stat().st_size > 0
    with pytest.warns(UserWarning, match="estimated"):
        camera = load_calibration(tmp_path / "cal" / "calibration.yaml")
    assert camera.static and camera.intrinsics[0, 0] == pytest.approx(summary["focal_px"], abs=0.01)
    assert camera.cam_to_vehicle[2, 3] == pytest.approx(summary["height_m"], abs=1e-3)


def test_intrinsics_from_a_field_of_view(tmp_path: Path) -> None:
    path = tmp_path / "fov.yaml"
    path.write_text("width: 1600\nheight: 900\nfov_deg: 64.5\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        width, height, k = load_intrinsics(path)
    assert (width, height) == (1600, 900)
    assert k is not None and k[0, 0] == pytest.approx(800 / np.tan(np.radians(32.25)))
    assert k[0, 2] == 800 and k[1, 2] == 450


@pytest.mark.parametrize(("calibration", "static", "expected"), [
    (None, True, True),            # a fixed camera, nothing given: estimated
    ("intrinsics", True, True),    # focal length given, the mounting estimated
    ("full", True, False),         # a placed camera is used as it is
    (None, False, False),          # a vehicle camera without a calibration is refused by the run's rules
    ("intrinsics", False, True),   # a vehicle camera's mounting is estimated (its ego poses given)
])
def test_which_runs_estimate_their_camera(tmp_path: Path, calibration: str | None, static: bool,
                                          expected: bool) -> None:
    from pedenv.apps.calibrate import needs_estimate

    files = {"intrinsics": "width: 640\nheight: 480\nfov_deg: 60\n",
             "full": "width: 640\nheight: 480\nfov_deg: 60\ncam_to_vehicle:\n  rotation: [0.5, -0.5, 0.5, -0.5]\n"
                     "  translation: [0, 0, 5]\n"}
    path = None
    if calibration is not None:
        path = tmp_path / "c.yaml"
        path.write_text(files[calibration])
    assert needs_estimate(tmp_path, None, path, static) is expected


@pytest.mark.parametrize("command", ["calibrate", "run"])
def test_a_recording_without_people_is_one_line_and_writes_nothing(monkeypatch: pytest.MonkeyPatch,
                                                                   capsys: pytest.CaptureFixture, tmp_path: Path,
                                                                   command: str) -> None:
    from pedenv.images import write_image

    from cli_in_process import pedenv

    folder = tmp_path / "empty"
    folder.mkdir()
    for index in range(5):
        write_image(folder / f"{index:06d}.jpg", np.full((120, 160, 3), 90, np.uint8))
    extra = ["--fps", "10", "--static"] if command == "run" else []
    code, _, err = pedenv(monkeypatch, capsys, command, "--images", folder, "--output", tmp_path / "out", *extra)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert err.startswith("error: too few upright people to estimate the camera: 0 person-images")
    assert "give --calibration" in err and not (tmp_path / "out").exists()


def test_a_warm_up_whose_people_do_not_fix_the_camera_goes_on(plaza: tuple[Path, tuple[Frame, ...]], tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch) -> None:
    import pedenv.calibration.refusals as refusals
    from pedenv.apps.calibrate import calibrate
    from pedenv.calibration.fit import FIT_STD_SCALE

    folder, frames = plaza
    monkeypatch.setattr(refusals, "MAX_FOCAL_RELATIVE_STD", 0.03)  # 3, 6, 9 frames leave 4.7, 3.5, 2.9 %
    summary = calibrate(output=tmp_path / "cal", source=RecordingSource(images=folder, static=True),
                        backend=SceneBackend(frames), frames=3)
    # the refusal judges the fit's own 1-sigma, the written one is FIT_STD_SCALE times it
    assert summary["warmup_frames"] == 9 and summary["std"]["focal_px"] <= 0.03 * FIT_STD_SCALE * summary["focal_px"]
    assert summary["focal_px"] == pytest.approx(parameters_of(frames[0].camera)[0], rel=0.1)
