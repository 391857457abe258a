"""The behaviour fields in the Parquet table, the overlay and the bird's-eye picture."""

import dataclasses

import numpy as np
import pyarrow.parquet as pq
import pytest

from pedenv.config import Config
from pedenv.model import PedestrianEnvironmentModel
from pedenv.outputs.parquet import BEHAVIOUR_COLUMNS, EnvironmentTableWriter
from pedenv.synthetic import generate_scenes
from pedenv.synthetic.detector import DetectorModel
from pedenv.visualize.behaviour_drawing import behaviour_label, draw_behaviour_image
from pedenv.visualize.birds_eye_video import BirdsEyeVideo


@pytest.fixture(scope="module")
def states():
    scene = generate_scenes(0, ["turn-intersection"], duration_s=2.0)[0]
    detector = DetectorModel(0)
    frames = [dataclasses.replace(f, detections=detector(f)) for f in scene.frames]
    out = {}
    for method in ("fused", "paper"):
        model = PedestrianEnvironmentModel(Config(method=method))
        out[method] = [(model.update(f), f) for f in frames]
    return out


@pytest.mark.parametrize("method", ["fused", "paper"])
def test_parquet_columns(tmp_path, states, method):
    with EnvironmentTableWriter(tmp_path / "env.parquet") as writer:
        for state, frame in states[method]:
            writer.write(state, frame)
    table = pq.read_table(tmp_path / "env.parquet")
    state = states[method][-1][0]
    last = table.filter(table["frame"].to_numpy() == state.frame_index).to_pydict()
    if method == "paper":
        assert all(v is None for name in BEHAVIOUR_COLUMNS for v in last[name])
        return
    b = state.pedestrians.behaviour
    assert np.allclose(last["yaw"], b.yaw) and np.allclose(last["conflict_probability"], b.conflict_probability)
    assert np.allclose(last["predicted_xy"], b.predicted_positions)
    assert last["horizons"][0] == [0.5, 1.0, 2.0, 3.0] and set(last["motion_state"]) <= {"standing", "walking",
                                                                                         "running"}


def test_overlay_and_birds_eye_draw_the_cues(states):
    state, frame = states["fused"][-1]
    image = np.zeros((frame.camera.height, frame.camera.width, 3), np.uint8)
    draw_behaviour_image(image, state, frame.camera.intrinsics, frame.cam_to_world)
    assert image.any()  # paths and arrows landed in the picture
    assert behaviour_label(state, 0).split()[0] in ("standing", "walking", "running")
    assert behaviour_label(states["paper"][-1][0], 0) == ""
    plain = BirdsEyeVideo("unused.mp4").draw(states["paper"][-1][0], frame)
    drawn = BirdsEyeVideo("unused.mp4").draw(state, frame)
    assert (drawn != plain).any()
