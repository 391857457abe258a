import numpy as np
import pytest

from pedenv.config import Config, FusedConfig
from pedenv.model import PedestrianEnvironmentModel
from pedenv.skeleton import ANKLE_KEYPOINTS

from fused_frames import make_frame

FUSED = Config(method="paper").replace(method="fused")  # the fused locator behind the paper's tracker


def run(frames, config=FUSED):
    model = PedestrianEnvironmentModel(config)
    return [model.update(f) for f in frames]


def test_standing_ego_uses_ground_and_height_and_says_why_not_triangulation():
    ground = np.array([[8.0, 1.5, 0.0], [30.0, -4.0, 0.0]])
    states = run([make_frame(ground, index=i, timestamp=0.1 * i) for i in range(4)])
    peds = states[-1].pedestrians
    assert peds.sources[0] == "ground+height;triangulation:no-baseline"
    assert peds.sources[1] == "height;ground:beyond-range;triangulation:no-baseline"
    assert states[0].pedestrians.sources[0].endswith("triangulation:no-history")
    np.testing.assert_allclose(peds.positions[:, :2], ground[:, :2], rtol=0.02, atol=0.1)


def test_driving_ego_triangulates_and_the_covariance_is_long_along_the_ray():
    ground = np.array([[30.0, 6.0, 0.0]])
    frames = [make_frame(ground, ego_xyz=(1.0 * i, 0.0, 0.0), index=i, timestamp=0.1 * i) for i in range(6)]
    peds = run(frames)[-1].pedestrians
    assert "triangulation" in peds.sources[0].split(";")[0]
    ray = (ground[0, :2] - [5.0, 0.0]) / np.linalg.norm(ground[0, :2] - [5.0, 0.0])
    vals, vecs = np.linalg.eigh(peds.covariances[0])
    assert abs(vecs[:, 1] @ ray) > 0.95 and vals[1] > 4 * vals[0]
    assert peds.keypoints_3d.shape == (1, 17, 3)


def test_bad_input_never_gives_nan():
    # no ankles, a person above the horizon on a rise, a skeleton with almost nothing seen
    ground = np.array([[10.0, 0.0, 0.0], [40.0, 2.0, 4.0], [15.0, -3.0, 0.0]])
    frame = make_frame(ground, pitch=0.04)
    conf = frame.detections.confidences.copy()
    conf[0, list(ANKLE_KEYPOINTS)] = 0.0
    conf[2, :] = 0.0
    conf[2, [9, 10]] = 1.0  # only the wrists
    from dataclasses import replace

    from pedenv.records import Detections
    frame = replace(frame, detections=Detections(frame.detections.keypoints, conf))
    peds = run([frame])[-1].pedestrians
    for array in (peds.positions, peds.covariances, peds.keypoints_3d, peds.distances):
        assert np.isfinite(array).all()
    assert "ground:no-ankles" in peds.sources[0]
    assert "ground:above-horizon" in peds.sources[1]
    assert peds.sources[2].startswith("box;")


@pytest.mark.parametrize("values, message", [
    ({"cues": ("ground", "magic")}, "fused.cues entry"),
    ({"cues": ()}, "at least one"),
    ({"person_height_std_m": 0.0}, "person_height_std_m"),
    ({"history_length": 0}, "history_length"),
    ({"keypoint_span_std": -0.1}, "fused.keypoint_span_std"),
])
def test_config_is_range_checked(values, message):
    with pytest.raises(ValueError, match=message):
        FusedConfig(**values)


def test_config_round_trip_and_cue_selection():
    cfg = Config().replace(method="fused", fused={"cues": "height,ground"})
    assert cfg.fused.cues == ("height", "ground")
    assert Config.from_dict(cfg.to_dict()) == cfg
    peds = run([make_frame(np.array([[9.0, 0.0, 0.0]]))], cfg)[-1].pedestrians
    assert peds.sources[0] == "ground+height"


def pointing_person_frames(ground, n_frames=7, speed_m_per_frame=0.8):
    """Frames of a standing person at ``ground`` (1, 3) holding both wrists 0.5 m out in
    front (towards -x, the ego), seen from an ego driving along +x; and the true skeleton."""
    from dataclasses import replace

    from pedenv.geometry import invert_transform, project
    from pedenv.records import Detections

    from fused_frames import upright_skeletons
    truth = upright_skeletons(ground, [1.72])
    truth[0, [9, 10], 0] -= 0.5  # wrists reaching towards the road
    truth[0, [9, 10], 2] += 0.4
    frames = []
    for i in range(n_frames):
        frame = make_frame(ground, ego_xyz=(speed_m_per_frame * i, 0.0, 0.0), index=i, timestamp=0.1 * i)
        px, _ = project(truth, frame.camera.intrinsics, invert_transform(frame.cam_to_world))
        frames.append(replace(frame, detections=Detections(px, frame.detections.confidences)))
    return frames, truth[0]


def test_the_3d_skeleton_is_triangulated_over_the_history():
    # a distinctive pose: a cut at the person's range would put the wrists ~0.45 m too far
    ground = np.array([[14.0, 5.0, 0.0]])
    frames, truth = pointing_person_frames(ground)
    exact = FUSED.replace(fused={"ankle_keypoint_offset_m": 0.0})  # the rendered ankles sit at the anatomical height
    peds = run(frames, exact)[-1].pedestrians
    error = np.linalg.norm(peds.keypoints_3d[0] - truth, axis=1)
    assert error.max() < 0.05  # metres, every keypoint, wrists included (exact detections)
    first = run(frames[:1])[-1].pedestrians  # no history yet: cut at the range along each ray
    assert np.linalg.norm(first.keypoints_3d[0, 9] - truth[9]) > 0.3


def test_the_reported_covariance_holds_the_per_person_part():
    # the unknown height repeats every frame: filtering must not shrink it away
    ground = np.array([[30.0, -4.0, 0.0]])
    states = run([make_frame(ground, index=i, timestamp=0.1 * i) for i in range(30)])
    cov = states[-1].pedestrians.covariances[0]
    ray = ground[0, :2] / np.linalg.norm(ground[0, :2])
    assert np.sqrt(ray @ cov @ ray) > 0.5 * 30.0 * 0.09 / 1.72  # at least half the height prior's spread


def test_the_ground_cue_corrects_a_tall_persons_height_prior_nearby():
    # 1.95 m against the 1.72 m prior: the height cue puts them 11.7 % too near at 8 m; the ground
    # cue (a flat road, exact ankles) pulls the fused position back (0.96 of the height cue's
    # error while the road's curvature spread was 0.008 per m). Beside people of the prior's
    # height: alone, a tall person reads in part as a raised ground (the scene's level)
    ground = np.array([[8.0, 2.0, 0.0], [7.0, -2.0, 0.0], [9.0, 4.0, 0.0], [10.0, -3.0, 0.0]])
    exact = FUSED.replace(fused={"ankle_keypoint_offset_m": 0.0})  # the rendered ankles sit at the anatomical height
    frames = [make_frame(ground, [1.95, 1.72, 1.72, 1.72], index=i, timestamp=0.1 * i) for i in range(10)]
    peds = run(frames, exact)[-1].pedestrians
    i = int(np.argmin(np.linalg.norm(peds.positions[:, :2] - ground[0, :2], axis=1)))
    assert peds.sources[i].startswith("ground+height")
    rel = np.linalg.norm(peds.positions[i, :2] - ground[0, :2]) / np.linalg.norm(ground[0, :2])
    assert rel < 0.75 * (1.0 - 1.72 / 1.95)


def test_the_locator_keeps_the_last_frames_cues_row_for_row():
    ground = np.array([[8.0, 1.5, 0.0], [30.0, -4.0, 0.0]])
    model = PedestrianEnvironmentModel(FUSED)
    for i in range(3):
        peds = model.update(make_frame(ground, index=i, timestamp=0.1 * i)).pedestrians
    cues = {q.name: q for q in model.locator.last_cues}
    assert sorted(cues) == ["ground", "height", "triangulation"]
    assert cues["ground"].valid.tolist() == [True, False]  # the second stands beyond 20 m
    assert cues["height"].valid.all() and not cues["triangulation"].valid.any()  # a standing ego
    np.testing.assert_allclose(cues["height"].positions, peds.positions[:, :2], rtol=0.05)


def test_triangulation_pairs_no_ray_across_a_gap_of_missed_frames():
    # B is missed in frames 3-5 while the ego drives on and B walks; with max_misses 5 its
    # track lives through the gap: its past rays stay behind, no pair spans the gap
    config = FUSED.replace(tracking={"max_misses": 5})
    a, b = np.array([40.0, -3.0, 0.0]), np.array([30.0, 6.0, 0.0])
    frames = []
    for i in range(10):
        walked = b + [0.0, 0.03 * i, 0.0]
        ground = np.array([a, walked]) if i < 3 or i > 5 else a[None]
        frames.append(make_frame(ground, ego_xyz=(0.6 * i, 0.0, 0.0), index=i, timestamp=0.1 * i))
    states = run(frames, config)
    before, after, later = (states[i].pedestrians for i in (2, 6, 9))
    assert after.track_ids[1] == before.track_ids[1]  # the same track came back
    assert after.sources[1].endswith("triangulation:no-history")
    assert "triangulation" in later.sources[1].split(";")[0].split("+")  # over the rays since the gap
    truth = b[:2] + [0.0, 0.03 * 9]
    assert np.linalg.norm(later.positions[1, :2] - truth) < 0.05 * np.linalg.norm(truth - [5.4, 0.0])
