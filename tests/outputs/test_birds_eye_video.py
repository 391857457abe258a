"""The animated bird's-eye view read back with OpenCV: one picture per frame, what is drawn where."""

import cv2
import numpy as np
import pytest
from sink_runs import FRAMES, FailingModel

from pedenv.records import EgoPose
from pedenv.state import EnvironmentState, Pedestrians
from pedenv.visualize.birds_eye_video import BirdsEyeVideo


def _frames(path) -> tuple[int, float, list[np.ndarray]]:
    cap = cv2.VideoCapture(str(path))
    count, fps = int(cap.get(cv2.CAP_PROP_FRAME_COUNT)), cap.get(cv2.CAP_PROP_FPS)
    pictures = []
    ok, img = cap.read()
    while ok:
        pictures.append(img)
        ok, img = cap.read()
    cap.release()
    return count, fps, pictures


def test_every_frame_of_every_scene_is_in_the_video(evaluated):
    folder, _, _ = evaluated
    count, fps, pictures = _frames(folder / "birds_eye.mp4")
    assert count == len(pictures) == 2 * FRAMES
    assert fps == pytest.approx(10.0)
    assert pictures[0].shape == (640, 640, 3)
    assert np.abs(pictures[1].astype(int) - pictures[-1].astype(int)).mean() > 1.0  # the picture moves


def test_a_run_stopped_by_a_bad_frame_leaves_a_video_of_the_finished_frames(interrupted):
    count, _, pictures = _frames(interrupted / "birds_eye.mp4")
    assert count == len(pictures) == FRAMES + FailingModel.FAIL_AT


def _state(positions, velocities) -> EnvironmentState:
    n = len(positions)
    z = np.zeros
    peds = Pedestrians(np.arange(1, n + 1), np.ones(n, np.int64), np.asarray(positions, float),
                       np.asarray(velocities, float), np.tile(np.eye(2) * 0.25, (n, 1, 1)), z((n, 17, 2)),
                       z((n, 17)), z((n, 4)), z((n, 17, 3)), np.ones(n), np.array(["test"] * n))
    return EnvironmentState(0, 0.0, EgoPose.from_xy_yaw(100.0, 50.0, np.pi / 2), peds, "s")


def test_a_pedestrian_ahead_is_drawn_above_the_ego_and_one_to_the_left_left_of_it(tmp_path):
    # ego at (100, 50) heading +y: world (100, 70) is 20 m ahead, (90, 60) is 10 m ahead and 10 m to the left
    video = BirdsEyeVideo(tmp_path / "b.mp4", size_px=400, ahead_m=40.0)
    img = video.draw(_state([[100.0, 70.0, 0.0], [90.0, 60.0, 0.0]], [[0, 0, 0], [0, 0, 0]]))
    red = (img[..., 2] > 180) & (img[..., 1] < 100) & (img[..., 0] < 100)
    scale = 0.9 * 400 / 40.0
    ego_u, ego_v = 200, 0.95 * 400
    for ahead, left in ((20.0, 0.0), (10.0, 10.0)):
        u, v = int(round(ego_u - left * scale)), int(round(ego_v - ahead * scale))
        assert red[v - 2:v + 3, u - 2:u + 3].all(), (ahead, left)


@pytest.mark.parametrize("options, message", [({"size_px": 50}, "size_px must be in"),
                                              ({"ahead_m": 1.0}, "ahead_m must be in")])
def test_options_are_range_checked(tmp_path, options, message):
    with pytest.raises(ValueError, match=message):
        BirdsEyeVideo(tmp_path / "b.mp4", **options)
