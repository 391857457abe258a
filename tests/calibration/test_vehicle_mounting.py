"""A vehicle camera's mounting from its direction of travel (the road) and the people: the cue, the
combination by uncertainties, the refusal, and the cue on real KITTI frames against GPS/IMU."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from pedenv.apps.options import RecordingSource
from pedenv.calibration.estimate import CameraEstimate
from pedenv.calibration.geometry import camera_rotation
from pedenv.calibration.observations import Observations
from pedenv.calibration.refusals import CalibrationRefused
from pedenv.calibration.road import (
    ROAD_SCALE_STD,
    STEP_SCALE_STD,
    TRAVEL_GROUND_STD_DEG,
    RoadCue,
    RoadScale,
    TravelWatcher,
    road_cue,
    road_scale,
    travel_direction,
)
from pedenv.calibration.vehicle import PEOPLE_GROUND_TILT_STD_DEG, combine, estimate_mounting, scaled, widen_people

from shared_paths import REAL_SAMPLES

RAW = REAL_SAMPLES / "kitti" / "raw_2011_09_26_drive_0002"


def _travel(tilt_deg: float, roll_deg: float, yaws_deg: np.ndarray, noise_deg: float, seed: int = 0) -> np.ndarray:
    """(N, 3) level travel directions (world) seen in the axes of a camera of ``tilt_deg``, ``roll_deg``."""
    rng = np.random.default_rng(seed)
    elevation = np.radians(rng.normal(0.0, noise_deg, len(yaws_deg)))
    yaw = np.radians(yaws_deg)
    world = np.c_[np.cos(elevation) * np.cos(yaw), np.cos(elevation) * np.sin(yaw), np.sin(elevation)]
    return world @ camera_rotation(np.radians(tilt_deg), np.radians(roll_deg))  # rows: R^T w


@pytest.mark.parametrize(("tilt_deg", "roll_deg"), [(2.0, 0.0), (-0.5, 1.5), (6.0, -2.0)])
def test_the_pooled_direction_of_travel_gives_the_pitch(tilt_deg: float, roll_deg: float) -> None:
    directions = _travel(tilt_deg, roll_deg, np.linspace(-8.0, 8.0, 200), noise_deg=0.4)
    directions[:5] = [0.0, -0.3, 0.95]  # five bad steps, far above the rest: left out
    cue = road_cue(directions)
    assert cue is not None and cue.steps == 195 and cue.dropped == 5
    assert np.degrees(cue.misfit(np.radians(tilt_deg), np.radians(roll_deg))) == pytest.approx(0.0, abs=0.1)
    assert np.degrees(cue.pitch) == pytest.approx(tilt_deg, abs=0.15)
    # the steps' scatter averages out; the direction of travel against the people's ground does not
    assert np.degrees(cue.std) == pytest.approx(np.hypot(0.4 / np.sqrt(195), TRAVEL_GROUND_STD_DEG), abs=0.01)


def test_a_step_seen_backwards_still_points_forward() -> None:
    rotation = np.eye(3)
    assert travel_direction(rotation, np.array([0.0, 0.0, -1.0]))[2] == pytest.approx(1.0)
    assert travel_direction(rotation, np.array([0.0, 0.0, 1.0]))[2] == pytest.approx(1.0)
    assert road_cue(np.zeros((0, 3))) is None


def _people(height: float, tilt_deg: float, std: tuple[float, float], correlation: float) -> CameraEstimate:
    sh, st = std[0], np.radians(std[1])
    cov = np.zeros((4, 4))
    cov[1:3, 1:3] = [[sh ** 2, correlation * sh * st], [correlation * sh * st, st ** 2]]
    cov[3, 3] = np.radians(0.2) ** 2
    return CameraEstimate(721.5, height, np.radians(tilt_deg), 0.0, cov, (1242, 375), (609.6, 172.9), 10, 200, 2.0,
                          True)


def test_the_road_moves_the_pitch_and_through_the_people_the_height() -> None:
    # the people put the camera 0.8 deg too far down and, correlated with it, 0.1 m too high
    people = widen_people(_people(1.75, 1.8, (0.03, 0.1), 0.9))
    road = RoadCue(_travel(1.0, 0.0, np.zeros(1), 0.0)[0], np.radians(0.2), 100)
    both = combine(people, road)
    s_people, s_both = people.std, both.std
    assert s_people[2] == pytest.approx(np.radians(np.hypot(0.1, PEOPLE_GROUND_TILT_STD_DEG)), rel=0.01)
    assert np.degrees(both.tilt) == pytest.approx(1.0 + 0.8 * 0.2 ** 2 / (0.2 ** 2 + np.degrees(s_people[2]) ** 2),
                                                  abs=0.02)
    assert both.height < people.height - 0.05  # the height follows the pitch down
    assert s_both[2] < min(s_people[2], road.std) and s_both[1] < s_people[1]
    assert both.road is not None and both.road["disagreement_sigma"] == pytest.approx(
        0.8 / np.hypot(0.2, np.degrees(s_people[2])), rel=0.02)


def test_a_parked_car_keeps_the_people_estimate_and_few_people_are_refused_naming_the_road() -> None:
    from pedenv.calibration.geometry import ground_points, intrinsics, project

    k = intrinsics(721.5, (609.6, 172.9))
    r = camera_rotation(np.radians(1.0), 0.0)
    rng = np.random.default_rng(3)
    feet_w = np.c_[rng.uniform(6, 30, 40), rng.uniform(-6, 6, 40), np.zeros(40)]
    feet = project(feet_w + [0, 0, 0.1], k, r, 1.65)
    heads = project(feet_w + [0, 0, 1.6], k, r, 1.65)
    assert np.isfinite(ground_points(feet, k, r, 1.65)).all()
    obs = Observations(feet, heads, np.full(40, 0.936), np.arange(40) % 8, np.arange(40) // 8)
    parked = estimate_mounting(obs, (1242, 375), focal=721.5, centre=(609.6, 172.9))
    assert parked.road is None and parked.height == pytest.approx(1.65, rel=0.1)
    few = obs.subset(obs.tracks < 3)
    road = RoadCue(np.array([0.0, -np.sin(np.radians(1.0)), np.cos(np.radians(1.0))]), np.radians(0.2), 50)
    with pytest.raises(CalibrationRefused, match=r"height cannot be estimated: too few .* road alone gave only the "
                                                 r"pitch \(1\.00 \+- 0\.20 deg from 50 steps.*ego poses"):
        estimate_mounting(few, (1242, 375), focal=721.5, centre=(609.6, 172.9), road=road)
    # with the ego poses the road's scale gives the height: the road alone then places the camera
    alone = estimate_mounting(few, (1242, 375), focal=721.5, centre=(609.6, 172.9), road=road,
                              scale=RoadScale(1.62, 0.05, 40))
    assert alone.people == 0 and alone.height == 1.62 and np.degrees(alone.tilt) == pytest.approx(1.0)
    assert alone.roll == 0.0 and alone.std[1] == pytest.approx(0.05) and alone.road is not None
    assert alone.road["scale"]["steps"] == 40 and alone.road["steps"] == 50


def test_the_road_scale_pools_the_steps_heights_and_leaves_out_the_wild_ones() -> None:
    rng = np.random.default_rng(1)
    ego = rng.uniform(0.5, 1.5, 60)
    odometry = ego * 1.5 / 1.62 * np.exp(rng.normal(0.0, 0.03, 60))
    odometry[:3] *= 2.0  # three steps whose road was a parked car's roof: their heights halved
    odometry[3], ego[4] = np.nan, 0.1  # a step without road, one too short to count
    scale = road_scale(odometry, ego)
    assert scale is not None and scale.steps == 55 and scale.dropped == 3
    assert scale.height == pytest.approx(1.62, rel=0.01)
    assert scale.std / scale.height == pytest.approx(np.hypot(scale.scatter / np.sqrt(55), ROAD_SCALE_STD), rel=1e-6)
    assert scale.scatter == pytest.approx(0.03, rel=0.3)
    few = road_scale(np.array([1.0]), np.array([1.1]))  # one step: the per-step spread assumed
    assert few is not None and few.height == pytest.approx(1.65) and few.std == pytest.approx(
        1.65 * np.hypot(STEP_SCALE_STD, ROAD_SCALE_STD))
    assert road_scale(np.array([np.nan]), np.array([1.0])) is None


def test_the_road_scale_corrects_short_people_and_the_pitch_follows() -> None:
    # short people put the camera 0.15 m too high; the tilt is correlated with the height
    people = _people(1.75, 1.0, (0.08, 0.3), 0.5)
    both = scaled(people, RoadScale(1.60, 0.05, 100))
    weight = 0.08 ** 2 / (0.08 ** 2 + 0.05 ** 2)
    assert both.height == pytest.approx(1.75 - 0.15 * weight, abs=1e-6)
    assert np.degrees(both.tilt) < 1.0 - 0.05  # the tilt follows the height down
    assert both.std[1] == pytest.approx(np.sqrt(0.08 ** 2 * 0.05 ** 2 / (0.08 ** 2 + 0.05 ** 2)), rel=1e-6)
    assert both.road is not None and both.road["people_height_m"] == 1.75
    assert both.road["height_disagreement_sigma"] == pytest.approx(0.15 / np.hypot(0.08, 0.05))


def test_real_kitti_frames_give_the_pitch_of_travel_and_the_height_of_the_gps_imu() -> None:
    from pedenv.images import read_image_rgb
    from pedenv.odometry.reference import integrated_distance, read_oxts

    line = next(t for t in (RAW / "calib_cam_to_cam.txt").read_text().splitlines() if t.startswith("P_rect_02:"))
    k = np.array(line.split()[1:], dtype=np.float64).reshape(3, 4)[:, :3]
    sync = RAW / "2011_09_26_drive_0002_sync"
    oxts = read_oxts(sorted((sync / "oxts" / "data").glob("*.txt"))[:5])
    stamps = np.array([np.datetime64(t.strip()) for t in (sync / "image_02" / "timestamps.txt").read_text().splitlines()
                       if t.strip()][:5])
    times = (stamps - stamps[0]) / np.timedelta64(1, "s")

    def gps_length(a: int, b: int) -> float:
        return integrated_distance(oxts[a:b + 1], times[a:b + 1])

    watcher = TravelWatcher(k, gps_length)
    frames = ((i, read_image_rgb(RAW / f"2011_09_26_drive_0002_sync/image_02/data/{i:010d}.png")) for i in range(5))
    assert [i for i, _ in watcher.watch(frames)] == [0, 1, 2, 3, 4]
    cue = watcher.cue()
    # GPS/IMU: the velocity's elevation in the camera's axes (calibrated chain), frames 0-4: -0.23 deg;
    # the IMU's forward axis -0.48 deg (benchmarks/vehicle_mounting.py --only road)
    assert cue is not None and cue.steps == 4 and watcher.refused == 0
    assert np.degrees(cue.pitch) == pytest.approx(-0.23, abs=0.5)
    assert np.degrees(cue.std) == pytest.approx(np.hypot(0.4 / 2, TRAVEL_GROUND_STD_DEG), abs=0.01)
    # the road's scale with GPS/IMU's step lengths: KITTI's camera is 1.65 m over the road
    # (all 9 steps of the drive: 1.607 m, benchmarks/vehicle_mounting.py --only road)
    scale = watcher.scale()
    assert scale is not None and scale.steps == 4
    assert scale.height == pytest.approx(1.65, rel=0.05)
    assert TravelWatcher(k).scale() is None  # no ego poses, no scale


def test_a_blank_recording_gives_no_road() -> None:
    watcher = TravelWatcher(np.array([[500.0, 0, 320], [0, 500.0, 240], [0, 0, 1]]))
    for i in range(4):
        watcher.add(i, np.full((480, 640), 90, np.uint8))
    # frame 1 is refused against frame 0, frame 2 starts afresh, frame 3 is refused against it
    assert watcher.cue() is None and watcher.refused == 2


def test_the_roll_is_held_level_by_the_mounting_prior() -> None:
    from pedenv.calibration.vehicle import MOUNT_ROLL_STD_DEG, PEOPLE_GROUND_ROLL_STD_DEG, level_roll

    people = widen_people(dataclasses.replace(_people(1.65, 1.0, (0.05, 0.1), 0.0), roll=np.radians(2.0)))
    spread = np.degrees(people.std[3])
    assert spread == pytest.approx(np.hypot(0.2, PEOPLE_GROUND_ROLL_STD_DEG), rel=0.01)
    level = level_roll(people)
    shrink = MOUNT_ROLL_STD_DEG ** 2 / (MOUNT_ROLL_STD_DEG ** 2 + spread ** 2)
    assert np.degrees(level.roll) == pytest.approx(2.0 * shrink, abs=0.01)
    assert np.degrees(level.std[3]) == pytest.approx(spread * np.sqrt(shrink), rel=0.01)
    assert level.height == pytest.approx(1.65) and level.tilt == pytest.approx(people.tilt)  # not correlated here


class _NoPeople:
    """A pose backend that finds nobody (the raw drive holds no pedestrians)."""

    name = "detector-model"

    def detect(self, _image: np.ndarray):
        from pedenv.records import Detections

        return Detections.empty()


def test_calibrate_a_vehicle_camera_without_people_names_the_road_pitch(tmp_path) -> None:
    from pedenv.apps.calibrate import calibrate

    intrinsics = tmp_path / "k.yaml"
    intrinsics.write_text("width: 1242\nheight: 375\nintrinsics: [[721.5377, 0, 609.5593], [0, 721.5377, 172.854], "
                          "[0, 0, 1]]\n")
    with pytest.raises(CalibrationRefused, match=r"the road alone gave only the pitch \(-0\.\d\d \+- 0\.\d\d deg from "
                                                 r"3 steps of travel\).*give cam_to_vehicle"):
        calibrate(output=tmp_path / "out", source=RecordingSource(
            images=RAW / "2011_09_26_drive_0002_sync/image_02/data", calibration=intrinsics, static=False),
            backend=_NoPeople(), frames=4)
    assert not (tmp_path / "out").exists()


def _gps_poses_and_intrinsics(tmp_path) -> tuple[list[float], Path, Path]:
    """KITTI raw 0002's GPS/IMU distance along a straight line as ego poses (one a frame at 10 Hz), and its
    intrinsics without a mounting."""
    from pedenv.odometry.reference import integrated_distance, read_oxts

    sync = RAW / "2011_09_26_drive_0002_sync"
    oxts = read_oxts(sorted((sync / "oxts" / "data").glob("*.txt")))
    stamps = np.array([np.datetime64(t.strip()) for t in (sync / "image_02" / "timestamps.txt").read_text().splitlines()
                       if t.strip()])
    times = (stamps - stamps[0]) / np.timedelta64(1, "s")
    along = [integrated_distance(oxts[: i + 1], times[: i + 1]) for i in range(len(oxts))]
    poses = tmp_path / "poses.csv"
    poses.write_text("timestamp,x,y,yaw\n" + "".join(f"{100 + i / 10:.1f},{x:.4f},0,0\n" for i, x in enumerate(along)))
    intrinsics = tmp_path / "k.yaml"
    intrinsics.write_text("width: 1242\nheight: 375\nintrinsics: [[721.5377, 0, 609.5593], [0, 721.5377, 172.854], "
                          "[0, 0, 1]]\n")
    return along, poses, intrinsics


def test_a_run_with_ego_poses_and_no_people_places_the_camera_from_the_road(tmp_path) -> None:
    from pedenv.apps.calibrate import ego_lengths, self_calibrate

    sync = RAW / "2011_09_26_drive_0002_sync"
    along, poses, intrinsics = _gps_poses_and_intrinsics(tmp_path)
    lengths = ego_lengths(poses, sync / "image_02" / "data", None, fps=10.0)
    assert lengths is not None and lengths(0, 2) == pytest.approx(along[2], abs=1e-4) and np.isnan(lengths(0, 99))
    found = self_calibrate(sync / "image_02" / "data", None, intrinsics, _NoPeople(), "detector-model",
                           mount="vehicle", ego_length=lengths)
    est = found.estimate
    # no people: the road's scale with GPS/IMU's steps (KITTI: 1.65 m) and its direction of travel
    assert est.people == 0 and est.height == pytest.approx(1.65, rel=0.05) and abs(np.degrees(est.tilt)) < 1.0
    (tmp_path / "out").mkdir()
    summary = found.write(tmp_path / "out")
    assert summary["road"]["scale"]["steps"] == 9 and (tmp_path / "out" / "calibration.png").is_file()


def test_calibrate_with_ego_poses_places_a_vehicle_camera_from_the_road(tmp_path) -> None:
    from pedenv.apps.calibrate import calibrate

    _, poses, intrinsics = _gps_poses_and_intrinsics(tmp_path)
    source = RecordingSource(images=RAW / "2011_09_26_drive_0002_sync/image_02/data", calibration=intrinsics,
                             ego_poses=poses, static=False, fps=10.0)
    summary = calibrate(output=tmp_path / "out", source=source, backend=_NoPeople())
    # the road's scale from GPS/IMU's steps (KITTI: 1.65 m); without the poses the same frames are refused (above)
    assert summary["people"] == 0 and summary["height_m"] == pytest.approx(1.65, rel=0.05)
    assert (tmp_path / "out" / "calibration.yaml").is_file()


def test_calibrate_refuses_ego_poses_for_a_static_camera(tmp_path) -> None:
    import subprocess
    import sys

    poses = tmp_path / "poses.csv"
    poses.write_text("timestamp,x,y,yaw\n0,0,0,0\n")
    result = subprocess.run([sys.executable, "-c", "from pedenv.cli import main; main()", "calibrate", "--images",
                             str(tmp_path), "--ego-poses", str(poses), "--output", str(tmp_path / "out")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "--ego-poses is for the mounting of a camera on a vehicle" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()
