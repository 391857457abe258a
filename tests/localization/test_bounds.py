"""Issue 10.2/10.3: no NaN, no inf and no position beyond the method's cap leaves the model."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pedenv import records
from pedenv.config import Config, FusedConfig
from pedenv.errors import InputError
from pedenv.localization import configure, create_locator
from pedenv.localization.base import Measurement
from pedenv.localization.bounds import CLAMPED, UNLOCALISED, bound_measurement, clamp_to_range
from pedenv.model import PedestrianEnvironmentModel
from pedenv.records import Camera, Detections, EgoPose, Frame

from standing_people import frame_with_people

CAMERA = Camera.from_fov()


def person_pixels(cx: float, top: float, height_px: float) -> np.ndarray:
    """(17, 2) pixels of a standing person ``height_px`` tall, top at ``top``."""
    frac = np.array([.92, .94, .94, .93, .93, .82, .82, .62, .62, .48, .48, .53, .53, .29, .29, .05, .05])
    lateral = np.array([0, .03, -.03, .07, -.07, .2, -.2, .24, -.24, .25, -.25, .1, -.1, .1, -.1, .1, -.1])
    return np.column_stack([cx + lateral * height_px * 0.3, top + (1 - frac) * height_px])


def frame(index: int, keypoints: np.ndarray, box=None) -> Frame:
    det = Detections(keypoints[None], np.ones((1, 17)), None if box is None else np.array([box], float))
    return Frame(index, 0.1 * index, CAMERA, EgoPose.from_xy_yaw(0.5 * index, 0.0, 0.0), detections=det)


@pytest.mark.parametrize("scale", [1e155, 1e19, 1e6])
def test_absurd_pixels_are_refused_naming_frame_and_bound(scale):
    kp = person_pixels(800, 400, 100) * np.array([scale / 800, 1.0])
    with pytest.raises(InputError, match=r"frame 4: detection 0 has pixels absurdly far outside the 1600x900 image.*"
                                         r"MAX_PIXEL_OFFSET_IMAGE_SIZES = 10"):
        frame(4, kp)
    # a box far out with sane keypoints is refused too
    with pytest.raises(InputError, match="frame 4: detection 0"):
        frame(4, person_pixels(800, 400, 100), [750, 400, scale, 500])


def test_pixels_a_few_image_sizes_out_are_data():
    f = frame(0, person_pixels(-3000, -500, 4000))  # a near person reaching far past the border
    assert len(f.detections) == 1


def test_pixel_bound_is_validated(monkeypatch):
    monkeypatch.setattr(records, "MAX_PIXEL_OFFSET_IMAGE_SIZES", 0.5)
    with pytest.raises(InputError, match=r"MAX_PIXEL_OFFSET_IMAGE_SIZES must be a number in \[1, 1000\], got 0.5"):
        frame(0, person_pixels(800, 400, 100))


PAPER = Config(method="paper")


class NaNOnce:
    """A locator of one's own wrapping the paper's, that returns NaN at one frame."""

    def __init__(self, config: Config, bad_frame: int) -> None:
        self.inner = create_locator(config)
        self.columns = self.inner.columns
        self.bad_frame = bad_frame

    def locate(self, geo, rows):
        meas = self.inner.locate(geo, rows)
        if geo.frame.index != self.bad_frame:
            return meas
        return Measurement(np.full_like(meas.positions, np.nan), np.full_like(meas.covariances, np.nan),
                           meas.sources, np.full_like(meas.keypoints_3d, np.inf))


def test_a_nan_measurement_never_poisons_the_track():
    """The issue's poisoning: one NaN measurement used to make every later frame of the track NaN."""
    model, reference = (
        PedestrianEnvironmentModel(PAPER, locator=NaNOnce(PAPER, bad_frame=3)),
        PedestrianEnvironmentModel(PAPER),
    )
    frames = [frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 1.0 + 0.1 * i)]) for i in range(8)]
    states = [model.update(f) for f in frames]
    expected = [reference.update(f) for f in frames]
    for s in states:
        p = s.pedestrians
        assert len(p) == 1 and p.track_ids.tolist() == [states[0].pedestrians.track_ids[0]]
        for name in ("positions", "velocities", "covariances", "keypoints_3d", "distances"):
            assert np.isfinite(getattr(p, name)).all(), (s.frame_index, name)
    assert states[3].pedestrians.sources.tolist() == [UNLOCALISED]
    # reported at the track's prediction, and the track goes on with real measurements
    between = 0.5 * (states[2].pedestrians.positions[0] + states[4].pedestrians.positions[0])
    assert states[3].pedestrians.positions[0, :2] == pytest.approx(between[:2], abs=1.0)
    assert states[7].pedestrians.positions[0, :2] == pytest.approx(expected[7].pedestrians.positions[0, :2], abs=0.5)
    assert np.isfinite(model.tracks.filter.x).all() and np.isfinite(model.tracks.filter.P).all()


def test_unlocalised_new_track_is_placed_at_the_cap_with_the_cap_as_spread():
    model = PedestrianEnvironmentModel(PAPER, locator=NaNOnce(PAPER, bad_frame=0))
    s = model.update(frame_with_people(0, 0.0, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))
    p = s.pedestrians
    assert p.sources.tolist() == [UNLOCALISED]
    assert np.hypot(*p.positions[0, :2]) == pytest.approx(500.0, abs=1e-6)  # camera at x = 0
    np.testing.assert_allclose(p.covariances[0], 500.0**2 * np.eye(2))
    assert not model.tracks.filter.started.any()


@pytest.mark.parametrize("height_px", [2.0, 0.01])
def test_fused_tiny_skeleton_is_clamped_to_max_range(height_px):
    """The issue: fused put a 2 px skeleton at 1.1 km and a 0.01 px one at 243 km."""
    model = PedestrianEnvironmentModel(configure(Config(), "fused"))
    assert model.max_range_m == FusedConfig().max_range_m == 200.0
    p = model.update(frame(0, person_pixels(800, 450, height_px))).pedestrians
    assert np.hypot(p.positions[0, 0], p.positions[0, 1]) == pytest.approx(200.0, abs=1e-6)
    assert p.sources[0].endswith(CLAMPED)
    bearing = p.positions[0, :2] / np.linalg.norm(p.positions[0, :2])
    assert bearing @ p.covariances[0] @ bearing >= 200.0**2  # the spread says the range is unknown


def test_fused_max_range_is_a_validated_config_value():
    with pytest.raises(ValueError, match=r"fused.max_range_m must be in \[5.0, 10000.0\], got 1.0"):
        FusedConfig(max_range_m=1.0)
    cfg = configure(Config(), "fused").replace(fused={"max_range_m": 50.0})
    p = PedestrianEnvironmentModel(cfg).update(frame(0, person_pixels(800, 450, 10.0))).pedestrians
    assert np.hypot(*p.positions[0, :2]) == pytest.approx(50.0, abs=1e-6)


def test_bound_measurement_hand_checked():
    origin = np.array([10.0, 0.0, 1.5])
    meas = Measurement(positions=np.array([[13.0, 4.0, 0.0], [1e300, 0.0, 0.0], [np.nan, 0.0, 0.0]]),
                       covariances=np.tile(np.eye(2), (3, 1, 1)), sources=np.array(["a", "b", "c"]),
                       keypoints_3d=np.zeros((3, 17, 3)))
    rays = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    out, measured = bound_measurement(meas, rays, origin, 0.0, 100.0)
    assert measured.tolist() == [True, True, False]
    np.testing.assert_allclose(out.positions, [[13.0, 4.0, 0.0], [110.0, 0.0, 0.0], [10.0, 100.0, 0.0]])
    assert out.sources.tolist() == ["a", "b" + CLAMPED, UNLOCALISED]
    np.testing.assert_allclose(out.covariances[1], [[1.0 + 100.0**2, 0.0], [0.0, 1.0]])
    np.testing.assert_allclose(out.covariances[2], 100.0**2 * np.eye(2))
    assert np.isfinite(out.keypoints_3d).all()
    pos, clamped, _ = clamp_to_range(np.array([[0.0, 0.0, 0.0], [10.0, 50.0, 0.0]]), origin, 30.0)
    assert clamped.tolist() == [False, True]
    np.testing.assert_allclose(pos[1], [10.0, 30.0, 0.0])


def test_paper_method_output_stays_within_its_cap():
    capped = PedestrianEnvironmentModel(PAPER.replace(paper={"max_distance_m": 40.0}))
    free = PedestrianEnvironmentModel(PAPER)
    for i in range(5):  # a person 60 m out, walking away
        f = frame_with_people(i, 0.1 * i, EgoPose.from_xy_yaw(0, 0, 0), [(60.0 + i, 0.0)])
        assert np.hypot(*capped.update(f).pedestrians.positions[0, :2]) <= 40.0 + 1e-9
        assert np.hypot(*free.update(f).pedestrians.positions[0, :2]) > 55.0


def test_environment_line_refuses_nan(tmp_path):
    """Every JSON writer uses allow_nan=False: a NaN would be a bug, never a NaN token in the file."""
    import json

    from pedenv.outputs.jsonl import EnvironmentWriter

    state = PedestrianEnvironmentModel().update(frame_with_people(0, 0.0, EgoPose.from_xy_yaw(0, 0, 0), [(20.0, 0.0)]))
    bad = replace(state, pedestrians=replace(state.pedestrians, distances=np.array([np.nan])))
    path = tmp_path / "environment.jsonl"
    with EnvironmentWriter(path) as writer:
        writer.write(state)
        with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
            writer.write(bad)
    lines = path.read_text().splitlines()
    assert len(lines) == 1 and "NaN" not in lines[0] and json.loads(lines[0])["frame"] == 0
