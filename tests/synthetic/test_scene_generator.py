"""The generated scenes: API, ground-truth consistency, visibility, statistics, seeds, terrain."""

from __future__ import annotations

import numpy as np
import pytest

from pedenv.geometry import invert_transform, project
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.generator import scene_terrain

from scene_checks import assert_scenes_equal

REQUIRED = ("red-light-crossing", "drive-30kmh-sidewalk", "drive-50kmh-sidewalk", "turn-intersection",
            "start-from-standstill", "crowd", "standing-pedestrians")


def all_frames(scenes):
    return [f for s in scenes for f in s.frames]


def test_required_scenarios_exist_in_default_order(default_scenes):
    assert set(REQUIRED) <= set(SCENARIOS)
    assert [s.name for s in default_scenes] == list(SCENARIOS)


@pytest.mark.parametrize("kwargs, message", [
    ({"names": ["highway"]}, "valid: red-light-crossing"),
    ({"frame_rate_hz": 0.0}, "frame_rate_hz"),
    ({"duration_s": -3.0}, "duration_s"),
    ({"seed": 1.5}, "seed must be an integer"),
])
def test_bad_options_raise_value_error(kwargs, message):
    with pytest.raises(ValueError, match=message):
        generate_scenes(**{"seed": 0, **kwargs})


def test_frames_are_numbered_timed_and_labelled(default_scenes):
    for scene in default_scenes:
        assert 15.0 <= len(scene) / 10.0 <= 25.0
        assert [f.index for f in scene.frames] == list(range(len(scene)))
        np.testing.assert_allclose([f.timestamp for f in scene.frames], np.arange(len(scene)) / 10.0)
        assert all(f.scene == scene.name and f.detections is None and f.ground_truth is not None for f in scene.frames)
        cam = scene.frames[0].camera
        assert (cam.width, cam.height) == (1600, 900)
        assert np.degrees(cam.hfov) == pytest.approx(64.5) and cam.cam_to_vehicle[2, 3] == 1.5


@pytest.mark.parametrize("frame_rate_hz, duration_s, frames, step", [(5.0, 4.0, 20, 0.2), (10.0, 2.0, 20, 0.1),
                                                                     (12.0, 1.0, 12, 1 / 12)])
def test_frame_rate_and_duration(frame_rate_hz, duration_s, frames, step):
    scene = generate_scenes(0, ["crowd"], frame_rate_hz=frame_rate_hz, duration_s=duration_s)[0]
    assert len(scene) == frames and scene.frames[1].timestamp == pytest.approx(step)


def test_keypoints_are_exact_projections_of_the_3d_skeletons(default_scenes, terrain_scenes):
    for frame in all_frames(default_scenes + terrain_scenes):
        gt = frame.ground_truth
        uv, depth = project(gt.keypoints_3d, frame.camera.intrinsics, invert_transform(frame.cam_to_world))
        np.testing.assert_allclose(gt.keypoints, uv, atol=1e-6)
        assert (depth > 0).all()


def test_kept_pedestrians_obey_the_visibility_rules(default_scenes):
    for frame in all_frames(default_scenes):
        gt = frame.ground_truth
        boxes, kp = gt.boxes, gt.keypoints
        assert (boxes[:, [0, 2]] >= 0).all() and (boxes[:, [0, 2]] <= 1600).all()
        assert (boxes[:, [1, 3]] >= 0).all() and (boxes[:, [1, 3]] <= 900).all()
        assert (np.ptp(kp[..., 1], axis=1) >= 15.0).all()
        inside = (kp[..., 0] >= 0) & (kp[..., 0] < 1600) & (kp[..., 1] >= 0) & (kp[..., 1] < 900)
        assert (inside.mean(axis=1) >= 0.6).all() and not gt.visible[~inside].any()
        distance = np.linalg.norm(gt.positions[:, :2] - frame.ego.translation[:2], axis=1)
        assert ((distance >= 5.0) & (distance <= 150.0)).all()
        assert len(set(gt.ids.tolist())) == len(gt)


def covered_by_nearer(boxes, depth, steps=20):
    """Fine-grid share of each box under the union of nearer boxes (an independent check)."""
    g = (np.arange(steps) + 0.5) / steps
    out = []
    for i, b in enumerate(boxes):
        u, v = np.meshgrid(b[0] + g * (b[2] - b[0]), b[1] + g * (b[3] - b[1]))
        near = boxes[depth < depth[i] - 0.3]
        hit = np.zeros(u.shape, bool)
        for o in near:
            hit |= (u >= o[0]) & (u <= o[2]) & (v >= o[1]) & (v <= o[3])
        out.append(hit.mean())
    return np.array(out)


def test_no_kept_pedestrian_is_mostly_hidden_by_nearer_kept_ones(default_scenes):
    crowd = default_scenes[SCENARIOS.index("crowd")]
    for frame in crowd.frames[::10]:
        gt = frame.ground_truth
        cam = (gt.keypoints_3d.reshape(-1, 3) - frame.cam_to_world[:3, 3]) @ frame.cam_to_world[:3, :3]
        depth = cam[:, 2].reshape(-1, 17).mean(axis=1)
        assert (covered_by_nearer(gt.boxes, depth) <= 0.5 + 0.1).all()


def test_ground_points_lie_on_the_terrain_and_feet_on_the_ground(terrain_scenes):
    for scene in terrain_scenes:
        terrain = scene_terrain(1, scene.name)
        for frame in scene.frames:
            gt = frame.ground_truth
            np.testing.assert_allclose(gt.positions[:, 2], terrain.height(gt.positions[:, :2]), atol=1e-9)
            ankles = gt.keypoints_3d[:, [KP.LEFT_ANKLE, KP.RIGHT_ANKLE], 2].min(axis=1) - gt.positions[:, 2]
            np.testing.assert_allclose(ankles, 0.046 * gt.heights, atol=0.02 * 1.98)


def test_terrain_grades_and_ego_pitch(default_scenes, terrain_scenes):
    steepest = 0.0
    for scene in terrain_scenes:
        assert 0.03 < scene_terrain(1, scene.name).max_grade <= 0.05
        pitch = np.degrees(np.abs([np.arcsin(-f.ego.rotation[2, 0]) for f in scene.frames]))
        assert 0.0 < pitch.max() < 4.5  # 5 % grade is 2.9 deg, plus about 1 deg of squat
        steepest = max(steepest, pitch.max())
    assert steepest > 0.5
    for frame in all_frames(default_scenes):
        assert np.array_equal(frame.ego.rotation[2], [0.0, 0.0, 1.0]) and frame.ego.translation[2] == 0.0


def test_turning_scene_yaw_rate(default_scenes):
    scene = default_scenes[SCENARIOS.index("turn-intersection")]
    yaw = np.unwrap([f.ego.yaw for f in scene.frames])
    rate = np.degrees(np.diff(yaw) / 0.1)
    assert np.abs(rate).max() == pytest.approx(20.0, abs=0.5)
    assert (np.abs(rate) > 19.0).sum() * 0.1 >= 3.5  # about 20 deg/s for several seconds
    assert abs(np.degrees(yaw[-1] - yaw[0])) == pytest.approx(90.0, abs=1.0)


def test_heights_and_walking_speeds_are_realistic(default_scenes):
    heights, speeds = {}, []
    for scene in default_scenes:
        previous = {}
        for frame in scene.frames:
            gt = frame.ground_truth
            here = dict(zip(gt.ids.tolist(), gt.positions[:, :2]))
            heights.update({(scene.name, i): h for i, h in zip(gt.ids.tolist(), gt.heights)})
            speeds += [np.linalg.norm(here[i] - previous[i]) / 0.1 for i in here.keys() & previous.keys()]
            previous = here
    h = np.array(list(heights.values()))
    assert len(h) > 300 and 1.69 < h.mean() < 1.75 and 0.07 < h.std() < 0.11
    assert h.min() >= 1.5 and h.max() <= 1.98
    moving = np.array(speeds)[np.array(speeds) > 0.05]
    assert moving.max() <= 1.61 and np.median(moving) == pytest.approx(1.3, abs=0.15)


def test_scene_statistics(default_scenes):
    counts = {s.name: np.mean([len(f.ground_truth) for f in s.frames]) for s in default_scenes}
    frames = all_frames(default_scenes)
    total = sum(len(f.ground_truth) for f in frames)
    assert 1000 <= len(frames) <= 2000 and 15_000 <= total <= 26_000
    assert all(10.0 <= c <= 30.0 for name, c in counts.items() if name != "crowd")
    assert counts["crowd"] > max(c for name, c in counts.items() if name != "crowd")
    distance = np.concatenate([np.linalg.norm(f.ground_truth.positions[:, :2] - f.ego.translation[:2], axis=1)
                               for f in frames])
    assert distance.min() < 8.0 and distance.max() > 120.0 and 40.0 < distance.mean() < 75.0
    standing = default_scenes[SCENARIOS.index("standing-pedestrians")]
    np.testing.assert_allclose(standing.frames[0].ego.translation, standing.frames[-1].ego.translation)


def test_seeds_reproduce_and_differ(default_scenes):
    a = generate_scenes(7, ["crowd", "turn-intersection"], duration_s=3.0)
    b = generate_scenes(7, ["crowd", "turn-intersection"], duration_s=3.0)
    c = generate_scenes(8, ["crowd", "turn-intersection"], duration_s=3.0)
    for x, y in zip(a, b):
        assert_scenes_equal(x, y)
    assert not np.array_equal(a[0].frames[0].ground_truth.positions[:3], c[0].frames[0].ground_truth.positions[:3])
    # a scenario generated alone equals the same scenario generated with all the others
    assert_scenes_equal(
        generate_scenes(0, "standing-pedestrians")[0], default_scenes[SCENARIOS.index("standing-pedestrians")]
    )
