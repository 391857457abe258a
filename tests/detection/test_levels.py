"""The far pyramid: levels by person height, the calibration-free height line, the level filter."""

import math

import numpy as np
import pytest

from pedenv.detection.config import BAND_MARGIN_PX, FIT_MARGIN, DetectionConfig
from pedenv.detection.levels import HeightLine, Level, plan_level, pyramid
from pedenv.detection.passes import level_filter
from pedenv.detection.tiling import Pass
from pedenv.records import Detections


def test_pyramid_of_a_nuscenes_frame_hands_each_height_to_one_level():
    levels = pyramid(1600, 900, DetectionConfig())
    assert [round(level.scale, 2) for level in levels] == [0.4, 1.0, 2.0]
    assert levels[0].min_height_px == pytest.approx(200) and levels[0].max_height_px == math.inf
    assert (levels[1].min_height_px, levels[1].max_height_px) == pytest.approx((80, 200))
    assert (levels[2].min_height_px, levels[2].max_height_px) == pytest.approx((40, 80))


@pytest.mark.parametrize("width, height, scales, expected", [
    (640, 480, (1.0, 2.0), [1.0, 2.0]),  # the whole-frame pass is already native: no x1 level
    (1600, 900, (0.3, 2.0), [0.4, 2.0]),  # a level below the whole-frame pass's scale is skipped
])
def test_levels_coarser_than_the_one_before_are_skipped(width, height, scales, expected):
    levels = pyramid(width, height, DetectionConfig(level_scales=scales))
    assert [round(level.scale, 2) for level in levels] == expected


def test_fast_has_one_level():
    assert len(pyramid(1600, 900, DetectionConfig(mode="fast"))) == 1


def people_on_a_line(slope, offset, feet):
    heights = slope * np.asarray(feet, float) + offset
    return np.column_stack([np.full(len(feet), 100.0), feet - heights, np.full(len(feet), 140.0), feet])


def test_height_line_recovers_the_line_and_drops_a_sitting_person():
    boxes = people_on_a_line(0.8, -320.0, [500, 600, 700, 800, 900])
    sitting = np.array([[300.0, 650, 340, 700]])  # 50 px tall where standing people are 240
    line = HeightLine.fit(np.vstack([boxes, sitting]), 3, 1080)
    assert (line.slope, line.offset, line.people) == pytest.approx((0.8, -320.0, 5))
    band = line.rows(40, 80, 10, 1080)
    # feet of a 40 px person at (40 + 320) / 0.8 = 450, of an 80 px one at 500; heads 410 and 420
    assert (band.top, band.bottom) == pytest.approx((400, 510), abs=1)


@pytest.mark.parametrize("boxes, why", [
    (people_on_a_line(0.8, -320.0, [500, 600]), "two people"),
    (people_on_a_line(0.8, -320.0, [600, 601, 602, 603]), "feet on one row"),
    (people_on_a_line(-0.5, 600.0, [500, 600, 700]), "taller higher up"),
    (np.zeros((0, 4)), "nobody"),
])
def test_height_line_refuses_what_it_cannot_fit(boxes, why):
    assert HeightLine.fit(boxes, 3, 1080) is None, why


def test_a_level_without_calibration_follows_the_fit_or_waits_for_it():
    config = DetectionConfig()
    level = Level(2.0, 40.0, 80.0)
    tiles, note = plan_level(level, 1920, 1080, config, None, None)
    assert tiles == [] and "skipped: no calibration, too few people" in note
    line = HeightLine(0.8, -320.0, 5)
    tiles, note = plan_level(level, 1920, 1080, config, None, line)
    margin = FIT_MARGIN * 80 + BAND_MARGIN_PX
    assert len({(p.region[1], p.region[3]) for p in tiles}) == 1  # one band
    assert (tiles[0].region[1], tiles[0].region[3]) == pytest.approx((410 - margin, 500 + margin), abs=1)
    assert "fit to 5" in note and all(p.kind == "band" for p in tiles)
    tiles, note = plan_level(Level(1.0, 80.0, 240.0), 1920, 1080, config, None, None)  # 2.07 megapixels
    assert [p.region for p in tiles] == [(0, 0, 1920, 1080)] and "whole image" in note


def detections(heights, scores, keypoint_conf):
    n = len(heights)
    boxes = np.column_stack([np.zeros(n), np.zeros(n), np.full(n, 20.0), heights])
    return Detections(np.zeros((n, 17, 2)), np.tile(np.asarray(keypoint_conf, float)[:, None], 17), boxes,
                      np.asarray(scores, float))


def test_level_filter_drops_fragments_and_unlikely_skeletons_of_finer_levels_only():
    dets = detections([100, 300, 100, 100], [0.9, 0.9, 0.3, 0.3], [0.9, 0.9, 0.7, 0.2])
    band = Pass((0, 0, 320, 100), (224, 640), "band")  # x2: 300 px is 600 px of its input
    assert level_filter(dets, band).tolist() == [True, False, True, False]
    full = Pass((0, 0, 1600, 900), (384, 640), "full")
    assert level_filter(dets, full).all()


def test_a_small_uncalibrated_image_gets_the_finest_level_over_all_of_it():
    tiles, note = plan_level(Level(2.0, 40.0, 80.0), 640, 480, DetectionConfig(), None, None)
    assert [(p.region, p.input_size) for p in tiles] == [((0, 0, 640, 480), (960, 1280))] and "whole image" in note
