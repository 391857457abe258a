"""Packed crops: packing, rendering, and persons found in a packed landing at the right image pixels."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pedenv.datasets.mot17 import read_sequence
from pedenv.detection.packing import (
    GAP_PX,
    Crop,
    crop_around,
    merge_crops,
    pack,
    pack_tallest_first,
    packed_units,
    render,
    unpack,
    used_size,
)
from pedenv.records import Detections

MOSAIC = (384, 640)


def person_in_packed(box_image: np.ndarray, placement) -> np.ndarray:
    """Where the image box (4,) px lies in the packed, input px."""
    x0, y0 = placement.crop.region[:2]
    ox, oy = placement.offset
    s = placement.crop.scale
    return np.array([(box_image[0] - x0) * s + ox, (box_image[1] - y0) * s + oy,
                     (box_image[2] - x0) * s + ox, (box_image[3] - y0) * s + oy])


def test_ten_far_people_fit_one_input_without_overlapping():
    boxes = [np.array([100.0 + 140 * i, 400, 118 + 140 * i, 445]) for i in range(10)]  # 45 px tall people
    crops = [crop_around(b, (900, 1600), 96.0, 0.35, 3.5, MOSAIC) for b in boxes]
    placed = pack(crops, MOSAIC)
    assert len(placed) == 10 and {p.packed for p in placed} == {0}
    rects = [(p.offset[0], p.offset[1], p.offset[0] + p.crop.size[1], p.offset[1] + p.crop.size[0]) for p in placed]
    for i, a in enumerate(rects):
        assert a[0] >= GAP_PX and a[1] >= GAP_PX and a[2] <= MOSAIC[1] and a[3] <= MOSAIC[0]
        for b in rects[i + 1:]:
            assert a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]
    assert all(p.crop.scale == pytest.approx(96.0 / 45.0) for p in placed)  # the person is 96 px tall there


def test_pack_keeps_order_and_limits_the_packed_inputs():
    crops = [Crop((0, 0, 100, 150), 2.0) for _ in range(12)]  # 300x200 input px each: 3 per packed input
    placed = pack(crops, MOSAIC, max_inputs=2)
    assert [p.item for p in placed] == list(range(6)) and [p.packed for p in placed] == [0, 0, 0, 1, 1, 1]
    assert pack([Crop((0, 0, 700, 100), 1.0)], MOSAIC) == []  # larger than the input: left out


def test_a_person_found_in_a_packed_crop_lands_at_the_right_image_pixels():
    image_boxes = np.array([[100.0, 400, 118, 445], [900, 380, 930, 450], [1400, 500, 1412, 530]])
    crops = [crop_around(b, (900, 1600), 112.0, 0.4, 3.5, MOSAIC) for b in image_boxes]
    placed = pack(crops, MOSAIC)
    in_packed = np.array([person_in_packed(image_boxes[p.item], p) for p in placed])
    kps = np.repeat(0.5 * (in_packed[:, None, :2] + in_packed[:, None, 2:]), 17, axis=1)
    found = Detections(kps, np.full((3, 17), 0.9), in_packed, np.array([0.9, 0.8, 0.7]))
    parts = unpack(found, placed, (900, 1600), 16.0)
    for p, (dets, cut) in zip(placed, parts):
        assert len(dets) == 1 and not cut[0]
        np.testing.assert_allclose(dets.boxes[0], image_boxes[p.item], atol=1e-6)
        np.testing.assert_allclose(dets.keypoints[0, 0], 0.5 * (image_boxes[p.item, :2] + image_boxes[p.item, 2:]))


def test_a_packed_input_is_trimmed_to_the_room_its_crops_use():
    crops = [Crop((0, 0, 50, 80), 1.5), Crop((0, 0, 40, 60), 1.5)]  # 120x75 and 90x60 input px
    placed = pack(crops, MOSAIC)
    assert [p.offset for p in placed] == [(GAP_PX, GAP_PX), (GAP_PX + 75 + GAP_PX, GAP_PX)]
    # extent: 4 + 120 = 124 rows, 4 + 75 + 4 + 60 = 143 columns, the gap after them, up to 32 px
    assert used_size(placed, MOSAIC) == (128, 160)
    assert packed_units(placed, MOSAIC, trim=True) == pytest.approx(128 * 160 / (384 * 640))
    assert packed_units(placed, MOSAIC, trim=False) == 1.0
    full = pack([Crop((0, 0, 200, 100), 3.0)] * 4, MOSAIC)  # four 300x600: two packed inputs, each whole
    assert {used_size([p for p in full if p.packed == m], MOSAIC) for m in (0, 1)} == {(320, 608)}  # 308 x 608
    image = np.random.default_rng(0).integers(0, 255, (200, 300, 3), dtype=np.uint8)
    trimmed = render(image, placed, used_size(placed, MOSAIC))
    np.testing.assert_array_equal(trimmed, render(image, placed, MOSAIC)[:128, :160])  # the same crops


def test_a_person_at_an_inner_crop_edge_is_cut():
    crop = Crop((100, 100, 200, 300), 1.0)
    placed = pack([crop], MOSAIC)
    ox, oy = placed[0].offset
    box = np.array([[ox + 1.0, oy + 50, ox + 30, oy + 150]])  # touching the crop's left edge (x 100, not the image's)
    dets, cut = unpack(Detections(np.zeros((1, 17, 2)) + box[:, None, :2], np.ones((1, 17)), box, np.ones(1)),
                       placed, (900, 1600), 16.0)[0]
    assert cut.tolist() == [True]


def test_render_puts_each_crop_scaled_at_its_offset():
    image = np.zeros((900, 1600, 3), np.uint8)
    image[400:445, 100:118] = 255
    crop = crop_around(np.array([100.0, 400, 118, 445]), (900, 1600), 90.0, 0.4, 3.5, MOSAIC)
    placed = pack([crop], MOSAIC)
    canvas = render(image, placed, MOSAIC)
    bright = np.argwhere(canvas[..., 0] > 200)
    ox, oy = placed[0].offset
    x0, y0 = crop.region[:2]
    assert bright[:, 0].min() == pytest.approx(oy + (400 - y0) * crop.scale, abs=2)
    assert bright[:, 1].min() == pytest.approx(ox + (100 - x0) * crop.scale, abs=2)
    assert bright[:, 0].max() - bright[:, 0].min() == pytest.approx(90, abs=3)


MOT17 = Path(__file__).resolve().parents[2].parent / "shared" / "samples" / "real" / "mot17"


def mot17_boxes(sequence: str, frame: int) -> tuple[np.ndarray, tuple[int, int]]:
    """The ground-truth boxes (N, 4) px of one real MOT17 frame and its (height, width)."""
    if not MOT17.is_dir():
        pytest.fail(f"{MOT17}: the real samples are missing (see /work/shared/samples/real/README.md)")
    seq = read_sequence(MOT17 / sequence)
    return seq.pedestrians.in_frame(frame).boxes, (seq.info.height, seq.info.width)


@pytest.mark.parametrize("sequence, frame, first_fit, tallest_first", [
    ("MOT17-02-FRCNN", 2, 2, 1),  # 22 people; crops clipped at the image's edges open short shelves
    ("MOT17-13-FRCNN", 2, 2, 1),  # 22 people seen from a bus, 24-224 px
    ("MOT17-04-FRCNN", 2, 2, 2),  # 42 people 110-251 px: 2 inputs either way
])
def test_tallest_first_packs_a_real_crowd_into_fewer_inputs(sequence, frame, first_fit, tallest_first):
    boxes, size = mot17_boxes(sequence, frame)
    crops = [crop_around(b, size, 80.0, 0.25, 3.5, MOSAIC) for b in boxes]
    assert len({p.packed for p in pack(crops, MOSAIC)}) == first_fit
    placed = pack_tallest_first(crops, MOSAIC)
    assert len(placed) == len(boxes) and len({p.packed for p in placed}) == tallest_first
    assert sorted(p.item for p in placed) == list(range(len(boxes)))


def test_denser_track_crops_hold_a_real_crowd_in_two_inputs():
    boxes, size = mot17_boxes("MOT17-04-FRCNN", 2)  # the crowd the whole-frame pass misses at night
    old = [crop_around(b, size, 96.0, 0.35, 3.5, MOSAIC) for b in boxes]
    new = [crop_around(b, size, 80.0, 0.25, 3.5, MOSAIC) for b in boxes]
    assert len(pack_tallest_first(old, MOSAIC, max_inputs=2)) == 26  # of 42: 4 inputs for all
    assert len(pack_tallest_first(new, MOSAIC, max_inputs=2)) == 42


def test_with_a_limit_the_first_crops_in_priority_order_are_kept():
    crops = [Crop((0, 0, 100, 150), 2.0) for _ in range(5)] + [Crop((0, 0, 50, 50), 1.0)]
    placed = pack_tallest_first(crops, MOSAIC, max_inputs=1)  # 3 tall ones fill the input's width
    assert sorted(p.item for p in placed) == [0, 1, 2, 5]  # the small one still fits beside them


def test_a_person_found_in_a_tallest_first_packed_crop_lands_at_the_right_image_pixels():
    boxes, size = mot17_boxes("MOT17-13-FRCNN", 2)
    crops = [replace(crop_around(b, size, 80.0, 0.25, 3.5, MOSAIC), edge_px=8.0) for b in boxes]
    placed = pack_tallest_first(crops, MOSAIC)
    in_packed = np.array([person_in_packed(boxes[p.item], p) for p in placed])
    kps = np.repeat(0.5 * (in_packed[:, None, :2] + in_packed[:, None, 2:]), 17, axis=1)
    found = Detections(kps, np.full((len(placed), 17), 0.9), in_packed, np.full(len(placed), 0.8))
    parts = unpack(found, placed, size, 16.0)
    for p, (dets, cut) in zip(placed, parts):
        assert len(dets) == 1 and not cut[0]  # 20 px of context around each: not cut at 8 px of edge
        np.testing.assert_allclose(dets.boxes[0], boxes[p.item], atol=1e-6)
    # an edge margin wider than the context (24 px) would cut them
    assert sum(bool(c[0]) for _, c in unpack(found, [replace(p, crop=replace(p.crop, edge_px=None)) for p in placed],
                                            size, 24.0)) > 0


def test_a_crop_can_cover_a_second_place_at_the_first_boxs_scale():
    box, last = np.array([500.0, 300, 530, 360]), np.array([470.0, 310, 500, 370])  # 60 px tall, 30 px apart
    crop = crop_around(box, (900, 1600), 96.0, 0.25, 3.5, MOSAIC, also=last)
    assert crop.region == (455, 285, 545, 385)  # both boxes with 15 px (0.25 of 60) around
    assert crop.scale == pytest.approx(96.0 / 60.0)


def test_a_narrow_box_gets_a_crop_around_its_own_width():
    box = np.array([254.0, 220, 284, 309])  # 89 px tall, 30 px wide: legs together (vtest.avi frame 0)
    plain = crop_around(box, (576, 768), 96.0, 0.35, 3.5, MOSAIC)
    assert plain.region == (222, 188, 316, 341)  # 0.35 x 89 = 31.15 px of context on each side


@pytest.mark.parametrize("second, ratio, joined", [
    ((520, 300, 560, 380), 1.25, True),  # overlapping neighbours of the same height: one crop
    ((900, 300, 940, 380), 1.25, False),  # far apart: one crop over both costs more input px
    ((520, 300, 560, 400), 1.25, True),  # 100 px against 80 px: scales within 1.25
    ((520, 300, 560, 420), 1.25, False),  # 120 px against 80 px: 1.5 apart
    ((520, 300, 560, 420), 1.5, True),
])
def test_neighbours_crops_are_joined_when_that_saves_input_px(second, ratio, joined):
    boxes = [np.array([500.0, 300, 540, 380]), np.array(second, float)]
    crops = [crop_around(b, (900, 1600), 80.0, 0.25, 3.5, MOSAIC) for b in boxes]
    merged, groups = merge_crops(crops, ratio, MOSAIC)
    if not joined:
        assert merged == crops and groups == [[0], [1]]
        return
    assert groups == [[0, 1]] and len(merged) == 1
    x0, y0, x1, y1 = merged[0].region
    assert (x0, y0) == (min(c.region[0] for c in crops), min(c.region[1] for c in crops))
    assert (x1, y1) == (max(c.region[2] for c in crops), max(c.region[3] for c in crops))
    assert merged[0].scale == min(c.scale for c in crops)  # the taller person at 80 px, the other a little less
    h, w = merged[0].size
    assert h * w <= sum(c.size[0] * c.size[1] for c in crops)


def test_a_person_found_in_a_joined_crop_lands_at_the_right_image_pixels():
    boxes = np.array([[500.0, 300, 540, 380], [525, 305, 563, 381], [540, 296, 580, 380]])
    crops = [crop_around(b, (900, 1600), 80.0, 0.25, 3.5, MOSAIC) for b in boxes]
    merged, groups = merge_crops(crops, 1.25, MOSAIC)
    assert groups == [[0, 1, 2]]
    placed = pack(merged, MOSAIC)
    in_packed = np.array([person_in_packed(b, placed[0]) for b in boxes])
    kps = np.repeat(0.5 * (in_packed[:, None, :2] + in_packed[:, None, 2:]), 17, axis=1)
    found = Detections(kps, np.full((3, 17), 0.9), in_packed, np.full(3, 0.8))
    (people, cut), = unpack(found, placed, (900, 1600), 4.0)
    np.testing.assert_allclose(people.boxes, boxes, atol=1e-6)
    assert not cut.any()  # all three inside the joined crop, none at its inner edges
