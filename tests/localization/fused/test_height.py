import numpy as np
import pytest

from pedenv.config import FusedConfig
from pedenv.localization.fused.height import height_cue
from pedenv.skeleton import ANKLE_KEYPOINTS, HEAD_KEYPOINTS
from pedenv.skeleton import CocoKeypoint as KP

from fused_frames import make_frame, skeletons_of

DEFAULT_FUSED = FusedConfig()


def run_height(frame, config=DEFAULT_FUSED, **kw):
    return height_cue(skeletons_of(frame, config), config, **kw)


def test_height_cue_is_exact_for_a_person_of_mean_height_on_a_rise_and_a_pitched_vehicle():
    # the height cue does not assume where the ground is: a person 0.8 m above the vehicle's plane
    ground = np.array([[8.0, 1.0, 0.8], [20.0, -3.0, -0.5], [45.0, 4.0, 1.2]])
    cue = run_height(make_frame(ground, pitch=0.03, roll=-0.01))
    assert cue.valid.all()
    rel = np.linalg.norm(cue.positions - ground[:, :2], axis=1) / np.linalg.norm(ground[:, :2] - [0, 0], axis=1)
    assert rel.max() < 0.01


def test_height_cue_scales_with_the_true_height_and_its_variance_holds_the_height_spread():
    ground = np.array([[20.0, 0.0, 0.0]])
    cue = run_height(make_frame(ground, heights=[1.72 * 1.05]))
    r = np.linalg.norm(cue.positions[0])
    assert r == pytest.approx(20.0 / 1.05, rel=0.01)
    sd_along = np.sqrt(cue.covariances[0, 0, 0] + cue.bias_covariances[0, 0, 0])
    assert sd_along > r * 0.09 / 1.72  # at least the spread of human heights
    assert sd_along < r * 0.08
    # the spread of heights and of the keypoint span (posture) repeat for the person: they
    # are the per-person part, all of it
    per_person = np.hypot(0.09 / 1.72, FusedConfig().keypoint_span_std)
    assert np.sqrt(cue.bias_covariances[0, 0, 0]) == pytest.approx(r * per_person, rel=1e-6)


def test_a_shorter_keypoint_span_brings_the_height_cue_nearer():
    ground = np.array([[20.0, 0.0, 0.0]])
    exact = np.linalg.norm(run_height(make_frame(ground)).positions[0])
    config = FusedConfig(keypoint_span_scale=0.9)
    short = np.linalg.norm(run_height(make_frame(ground), config).positions[0])
    assert short == pytest.approx(0.9 * exact, rel=0.03)


def test_height_cue_without_ankles_uses_head_shoulders_and_hips():
    cue = run_height(make_frame(np.array([[15.0, 0.0, 0.0]]), hidden=ANKLE_KEYPOINTS + (KP.LEFT_KNEE, KP.RIGHT_KNEE)))
    assert cue.valid[0]
    assert np.linalg.norm(cue.positions[0]) == pytest.approx(15.0, rel=0.02)


@pytest.mark.parametrize("hidden, reason", [
    (tuple(range(17)), "no-keypoints"),
    (tuple(k for k in range(17) if k not in HEAD_KEYPOINTS), "short-extent"),
])
def test_height_cue_declines_with_a_reason(hidden, reason):
    cue = run_height(make_frame(np.array([[15.0, 0.0, 0.0]]), hidden=hidden))
    assert not cue.valid[0] and cue.reason_names[0] == reason
    assert np.isfinite(cue.positions).all()


def test_height_cue_declines_for_an_upside_down_skeleton():
    frame = make_frame(np.array([[15.0, 0.0, 0.0]]))
    kp = frame.detections.keypoints.copy()
    kp[..., 1] = 900 - kp[..., 1]
    from dataclasses import replace

    from pedenv.records import Detections
    cue = run_height(replace(frame, detections=Detections(kp, frame.detections.confidences)))
    assert not cue.valid[0] and cue.reason_names[0] == "inconsistent"


def lift_left_ankle(frame, share):
    """The left ankle raised by ``share`` of the skeleton's pixel height (a swing foot)."""
    from dataclasses import replace

    from pedenv.records import Detections
    kp = frame.detections.keypoints.copy()
    kp[:, KP.LEFT_ANKLE, 1] -= share * np.ptp(kp[..., 1], axis=1)
    return replace(frame, detections=Detections(kp, frame.detections.confidences))


@pytest.mark.parametrize("distance", [8.0, 15.0, 30.0])
def test_a_lifted_swing_foot_is_left_out(distance):
    ground = np.array([[distance, 1.0, 0.0]])
    frame = lift_left_ankle(make_frame(ground), 0.15)
    cue = run_height(frame)
    assert np.linalg.norm(cue.positions[0] - ground[0, :2]) / distance < 0.01
    skel = skeletons_of(frame)
    assert skel.stance[0].tolist() == [False, True] and not skel.lone[0]


def test_noisy_standing_ankles_are_both_kept():
    frame = lift_left_ankle(make_frame(np.array([[40.0, 0.0, 0.0]])), 0.02)  # within pixel noise
    assert skeletons_of(frame).stance[0].all()


@pytest.mark.parametrize("reference, scaled_at", [(21.0, 21.0), (np.nan, 20.0), (3.0, 20.0), (150.0, 20.0)])
def test_the_variance_is_scaled_at_the_tracks_last_range_only_while_this_range_agrees(reference, scaled_at):
    """21 m lies within the cue's spread of 20 m: the track's range scales the variance. A
    last range of 3 m or 150 m belongs to someone else (or a long gap): this frame's does."""
    cue = run_height(make_frame(np.array([[20.0, 0.0, 0.0]])), reference_range=np.array([reference]))
    per_person = np.hypot(0.09 / 1.72, FusedConfig().keypoint_span_std)
    assert np.sqrt(cue.bias_covariances[0, 0, 0]) == pytest.approx(scaled_at * per_person, rel=0.02)
