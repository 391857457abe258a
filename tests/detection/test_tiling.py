"""Detection passes: the config's checks, the far band from the camera geometry, the tile plan."""

import math

import numpy as np
import pytest

from pedenv.detection.config import BAND_MARGIN_PX, MAX_TILES, DetectionConfig
from pedenv.detection.geometry import CameraGeometry, far_band
from pedenv.detection.levels import plan_passes
from pedenv.detection.tiling import fit_input
from pedenv.errors import InputError

NUSCENES_K = np.array([[1266.4, 0, 816.3], [0, 1266.4, 491.5], [0, 0, 1]])
KITTI_K = np.array([[707.05, 0, 604.08], [0, 707.05, 180.51], [0, 0, 1]])


@pytest.mark.parametrize("width, height, long_side, expected", [
    (1600, 900, 640, (384, 640)), (1224, 370, 640, (224, 640)), (1242, 375, 768, (256, 768)),
    (640, 480, 640, (480, 640)), (900, 1600, 640, (640, 384)), (100, 100, 640, (640, 640)),
])
def test_fit_input_follows_the_aspect(width, height, long_side, expected):
    assert fit_input(width, height, long_side) == expected


@pytest.mark.parametrize("field, value, message", [
    ("mode", "slow", "mode must be one of fast, far"),
    ("base_long_side", 650, "multiple of 32"),
    ("base_long_side", 64, r"base_long_side must be an integer in \[160, 2048\]"),
    ("tile_width", 100, r"detection.tile_width must be an integer in \[160, 4096\]"),
    ("level_scales", (2.0, 1.0), "ascending without repeats"),
    ("level_scales", (1.0, 5.0), r"detection.level_scales must be in \[0.25, 4.0\]"),
    ("level_scales", [1.0], "non-empty tuple"),
    ("near_m", 200.0, "near_m .* must be below detection.far_m"),
    ("min_person_px", True, "min_person_px"),
    ("far_m", 2000.0, r"detection.far_m must be in \[0.5, 1000.0\]"),
])
def test_config_fields_are_checked(field, value, message):
    with pytest.raises(ValueError, match=message):
        DetectionConfig(**{field: value})


def test_band_of_a_level_nuscenes_camera_matches_the_ground_at_15_and_150_m():
    geometry = CameraGeometry.level(NUSCENES_K, 1.5)
    config = DetectionConfig(near_m=15.0)
    band = far_band(geometry, 1600, 900, config)
    f, cy = 1266.4, 491.5
    assert band.bottom == pytest.approx(cy + f * 1.5 / 15 + BAND_MARGIN_PX, abs=2)  # feet at 15 m, the margin below
    assert band.top == pytest.approx(cy - f * 0.7 / 15 - BAND_MARGIN_PX, abs=2)  # a 2.2 m top at 15 m
    assert band.bottom - band.top < 200 + 2 * BAND_MARGIN_PX


def test_pitch_down_moves_the_band_up_and_roll_widens_it():
    config = DetectionConfig()
    level = far_band(CameraGeometry.level(NUSCENES_K, 1.5), 1600, 900, config)
    pitched = far_band(CameraGeometry.level(NUSCENES_K, 1.5, pitch_down_rad=math.radians(3)), 1600, 900, config)
    rolled = far_band(CameraGeometry.level(NUSCENES_K, 1.5, roll_rad=math.radians(3)), 1600, 900, config)
    shift = 1266.4 * math.tan(math.radians(3))
    assert pitched.top == pytest.approx(level.top - shift, abs=6)
    assert rolled.bottom - rolled.top > level.bottom - level.top + 30


@pytest.mark.parametrize(
    "geometry, config, why",
    [
        (None, DetectionConfig(), "no calibration"),
        (CameraGeometry.level(NUSCENES_K, 8.0, pitch_down_rad=math.radians(35)), DetectionConfig(), "looking down"),
        (
            CameraGeometry.level(NUSCENES_K, 1.5, pitch_down_rad=math.radians(-60)),
            DetectionConfig(),
            "looking at the sky",
        ),
        (
            CameraGeometry.level(NUSCENES_K, 1.5, pitch_down_rad=math.radians(-29)),
            DetectionConfig(),
            "band below the image",
        ),
        (CameraGeometry.level(NUSCENES_K, -1.0), DetectionConfig(), "camera below the ground"),
    ],
)
def test_no_band_falls_back_to_the_whole_image_at_native_scale(geometry, config, why):
    assert far_band(geometry, 1600, 900, config) is None, why
    passes, note = plan_passes(1600, 900, config, geometry)
    assert "calibration" in note and "x2 skipped: no calibration, too few people to fit" in note
    tiles = passes[1:]
    assert {p.kind for p in tiles} == {"tile"} and all(p.scale == pytest.approx(1.0, rel=0.03) for p in tiles)
    covered = np.zeros((900, 1600), bool)
    for p in tiles:
        x0, y0, x1, y1 = p.region
        covered[y0:y1, x0:x1] = True
    assert covered.all()


def test_far_plan_on_kitti_puts_each_level_where_its_people_stand():
    passes, note = plan_passes(1224, 370, DetectionConfig(), CameraGeometry.level(KITTI_K, 1.65))
    assert passes[0].kind == "full" and passes[0].input_size == (224, 640)
    assert all(p.kind == "band" for p in passes[1:]) and "(calibration)" in note
    native = [p for p in passes[1:] if p.scale == pytest.approx(1.0, rel=0.03)]
    double = [p for p in passes[1:] if p.scale == pytest.approx(2.0, rel=0.03)]
    assert len(native) + len(double) == len(passes) - 1 and native and double
    # x2 is for people 40-80 px tall: 13.3 m (1.5 m tall) to 38.9 m (2.2 m) away, feet to head
    f, cy, margin = 707.05, 180.51, 16
    top, bottom = double[0].region[1], double[0].region[3]
    # the top: the highest head of a person at most 80 px tall, a 2.2 m one at f * 2.2 / 80 = 19.4 m
    assert top == pytest.approx(cy - f * (2.2 - 1.65) / (f * 2.2 / 80) - margin, abs=3)
    assert bottom == pytest.approx(cy + f * 1.65 / 13.3 + margin, abs=3)
    assert double[0].region[0] == 0 and double[-1].region[2] == 1224  # the whole width
    assert all(p.input_size[0] % 32 == 0 and p.input_size[1] % 32 == 0 for p in passes)


def test_fast_is_one_pass():
    passes, note = plan_passes(1600, 900, DetectionConfig(mode="fast"), CameraGeometry.level(NUSCENES_K, 1.5))
    assert len(passes) == 1 and passes[0].input_size == (384, 640) and note == "one pass"


@pytest.mark.parametrize("width, height", [(100, 100), (8000, 6000), (20000, 40)])
def test_tiny_and_huge_images_get_a_bounded_plan(width, height):
    config = DetectionConfig()
    passes, _ = plan_passes(width, height, config)
    assert 1 <= len(passes) <= len(config.level_scales) * MAX_TILES + 1
    for p in passes:
        x0, y0, x1, y1 = p.region
        assert 0 <= x0 < x1 <= width and 0 <= y0 < y1 <= height
        assert p.input_size[0] <= config.tile_width and p.input_size[1] <= config.tile_width


def test_an_image_smaller_than_8_px_is_an_input_error():
    with pytest.raises(InputError, match="4x100 px is too small"):
        plan_passes(4, 100, DetectionConfig())
