"""A stand-in for a pose network on the synthetic scenes: noisy detections from the ground truth.

The model imitates a YOLO-pose style network from each frame's exact skeletons:

* a person of pixel height ``h`` (keypoint extent) is detected with probability
  ``1 / (1 + exp(-(h - half_detection_height_px) / detection_slope_px))`` (50 % at 25 px,
  98 % above 80 px by default), so far pedestrians are missed more often;
* keypoint positions get Gaussian noise whose standard deviation falls from
  ``noise_px_small`` at 30 px tall to ``noise_px_large`` at 300 px (a power law in
  ``h``), larger on wrists and ankles, and much larger on keypoints the camera does
  not see (outside the image or hidden), which are still guessed inside the image;
* each person's whole skeleton is also shifted by an offset that stays with that person
  from frame to frame (``person_offset_u`` sideways, ``person_offset_v`` up or down, as
  standard deviations in units of the person's keypoint extent): a real network places one
  person's ankles or body centre consistently off, and tracks do not average that away;
* per-keypoint confidences are high for large persons, lower for small ones, near the
  image border and on wrists and ankles, and low for unseen keypoints;
* a few small skeleton-shaped false positives appear (``false_positives_per_frame``).

The numbers come from a named profile (:mod:`pedenv.synthetic.detector_profiles`): the
hand-set ``default``, or values fitted to a real network on real images.

Random numbers depend only on ``(seed, scene name, frame index)``, a person's offset only on
``(seed, scene name, person id)``: reruns reproduce.
"""

from __future__ import annotations

import zlib

import numpy as np

from pedenv.errors import InputError
from pedenv.records import Detections, Frame, boxes_from_keypoints
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic.detector_profiles import DEFAULT_PROFILE, PROFILES, profile_parameters
from pedenv.synthetic.walker import body_keypoints
from pedenv.validation import check_number

__all__ = ["DEFAULT_PROFILE", "PROFILES", "DetectorModel"]

_EXTREMITIES = np.array([KP.LEFT_WRIST, KP.RIGHT_WRIST, KP.LEFT_ANKLE, KP.RIGHT_ANKLE])
_FACE = np.array([KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE, KP.LEFT_EAR, KP.RIGHT_EAR])


def _check(name: str, value: float, low: float, high: float) -> float:
    check_number(f"DetectorModel {name}", value, low, high)
    return float(value)


class DetectorModel:
    """The ``detector-model`` pose backend: detections simulated from ground-truth skeletons.

    seed: random seed (with the scene name and frame index it fixes every draw).
    profile: a named set of the values below (:data:`PROFILES`): ``default`` (the hand-set
        model), or one fitted to a real network, e.g. ``yolo11n-pose-single``. A value given
        explicitly overrides the profile's.
    noise_px_large: keypoint noise standard deviation (px) for a 300 px tall person.
    noise_px_small: the same for a 30 px tall person. Raising either makes every
        position estimate noisier; the noise follows a power law in between and beyond.
    extremity_noise_factor: wrists and ankles get this times more noise.
    unseen_noise_factor: keypoints the camera does not see get this times more noise.
    half_detection_height_px: pixel height at which half of the persons are detected.
        Raising it misses more distant pedestrians.
    detection_slope_px: width of the logistic detection curve in pixels; the default
        puts 98 % detection at about 80 px.
    false_positives_per_frame: mean number of spurious skeletons per frame (Poisson).
    box_noise_fraction: standard deviation of each edge of a detected person's box, as a
        share of its height (the box comes from the network's box head, not from the noisy
        keypoints). Raising it makes boxes, and so the association, less precise.
    box_min_confidence: a false positive's box spans its keypoints at least this confident.
    person_offset_u, person_offset_v: standard deviations of each person's persistent
        skeleton offset, sideways and vertical, as shares of the person's keypoint extent
        (0 in the hand-set profile). Raising them makes each track's bias, which no filter
        averages away, larger.
    """

    name = "detector-model"

    def __init__(self, seed: int = 0, *, profile: str | None = None, noise_px_large: float | None = None,
                 noise_px_small: float | None = None, extremity_noise_factor: float | None = None,
                 unseen_noise_factor: float | None = None, half_detection_height_px: float | None = None,
                 detection_slope_px: float | None = None, false_positives_per_frame: float | None = None,
                 box_noise_fraction: float | None = None, box_min_confidence: float | None = None,
                 person_offset_u: float | None = None, person_offset_v: float | None = None) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise InputError(f"DetectorModel seed must be an integer, got {seed!r}")
        self.seed = int(seed)
        self.profile = profile or DEFAULT_PROFILE
        given = {"noise_px_large": noise_px_large, "noise_px_small": noise_px_small,
                 "extremity_noise_factor": extremity_noise_factor, "unseen_noise_factor": unseen_noise_factor,
                 "half_detection_height_px": half_detection_height_px, "detection_slope_px": detection_slope_px,
                 "false_positives_per_frame": false_positives_per_frame, "box_noise_fraction": box_noise_fraction,
                 "box_min_confidence": box_min_confidence, "person_offset_u": person_offset_u,
                 "person_offset_v": person_offset_v}
        values = {**profile_parameters(self.profile), **{k: v for k, v in given.items() if v is not None}}
        self.noise_px_large = _check("noise_px_large", values["noise_px_large"], 0.0, 50.0)
        self.noise_px_small = _check("noise_px_small", values["noise_px_small"], 0.0, 50.0)
        self.extremity_noise_factor = _check("extremity_noise_factor", values["extremity_noise_factor"], 1.0, 10.0)
        self.unseen_noise_factor = _check("unseen_noise_factor", values["unseen_noise_factor"], 1.0, 20.0)
        self.half_detection_height_px = _check("half_detection_height_px", values["half_detection_height_px"],
                                               0.0, 1000.0)
        self.detection_slope_px = _check("detection_slope_px", values["detection_slope_px"], 0.1, 500.0)
        self.false_positives_per_frame = _check("false_positives_per_frame", values["false_positives_per_frame"],
                                                0.0, 20.0)
        self.box_min_confidence = _check("box_min_confidence", values["box_min_confidence"], 0.0, 1.0)
        self.box_noise_fraction = _check("box_noise_fraction", values["box_noise_fraction"], 0.0, 1.0)
        self.person_offset_u = _check("person_offset_u", values["person_offset_u"], 0.0, 0.5)
        self.person_offset_v = _check("person_offset_v", values["person_offset_v"], 0.0, 0.5)

    def noise_std_px(self, height_px: np.ndarray) -> np.ndarray:
        """Keypoint noise standard deviation (px) of persons ``height_px`` (N,) pixels tall."""
        if self.noise_px_large == 0.0 or self.noise_px_small == 0.0:
            return np.interp(height_px, [30.0, 300.0], [self.noise_px_small, self.noise_px_large])
        exponent = np.log(self.noise_px_small / self.noise_px_large) / np.log(30.0 / 300.0)
        return self.noise_px_large * (np.clip(height_px, 5.0, 2000.0) / 300.0) ** exponent

    def detection_probability(self, height_px: np.ndarray) -> np.ndarray:
        """Probability (N,) that persons ``height_px`` (N,) pixels tall are detected."""
        return 1.0 / (
            1.0 + np.exp(-(np.asarray(height_px, float) - self.half_detection_height_px) / self.detection_slope_px)
        )

    def __call__(self, frame: Frame) -> Detections:
        gt = frame.ground_truth
        if gt is None or (gt.keypoints is None and len(gt) > 0):
            raise InputError(f"frame {frame.index} of {frame.scene or 'the sequence'}: the detector-model backend "
                             "needs ground-truth skeletons")
        rng = np.random.default_rng([self.seed & 0xFFFFFFFF, zlib.crc32(frame.scene.encode()), int(frame.index)])
        w, h = frame.camera.width, frame.camera.height
        if gt.keypoints is None:  # a frame with nobody in it
            kp, seen = np.zeros((0, 17, 2)), np.zeros((0, 17), bool)
        else:
            assert gt.visible is not None  # GroundTruth sets visible whenever it has keypoints
            kp, seen = gt.keypoints, gt.visible
        n = kp.shape[0]
        height = np.ptp(kp[..., 1], axis=1) if n else np.zeros(0)
        detected = rng.random(n) < self.detection_probability(height)

        sigma = np.repeat(self.noise_std_px(height)[:, None], kp.shape[1], axis=1)
        sigma[:, _EXTREMITIES] *= self.extremity_noise_factor
        sigma = np.where(seen, sigma, self.unseen_noise_factor * sigma + 0.03 * height[:, None])
        noisy = kp + rng.normal(size=kp.shape) * sigma[..., None] + self._person_offsets(frame.scene, gt.ids, height)
        noisy = np.clip(noisy, 0.0, [w - 1.0, h - 1.0])  # networks place guesses inside the image

        size = 1.0 / (1.0 + np.exp(-(height - 40.0) / 20.0))  # 0.27 at 20 px .. 1 for large persons
        conf = 0.35 + 0.6 * size[:, None] + rng.normal(0.0, 0.05, seen.shape)
        conf[:, _EXTREMITIES] -= 0.08
        conf[:, _FACE] -= 0.05 * (1.0 - size[:, None])
        margin = np.minimum.reduce([noisy[..., 0], noisy[..., 1], w - 1.0 - noisy[..., 0], h - 1.0 - noisy[..., 1]])
        conf = np.where(margin < 0.01 * w, 0.8 * conf, conf)
        conf = np.where(seen, np.clip(conf, 0.05, 0.99), rng.uniform(0.02, 0.25, seen.shape))

        keep = np.flatnonzero(detected)
        fp_kp, fp_conf = self._false_positives(rng, w, h)
        keypoints = np.concatenate([noisy[keep], fp_kp])
        confidences = np.concatenate([conf[keep], fp_conf])
        order = rng.permutation(keypoints.shape[0])  # networks report persons in no particular order
        # A one-stage network regresses the person's box in its own head: the true box with
        # edges off by a share of the height, not the hull of the noisy keypoints.
        true_box = boxes_from_keypoints(kp[keep], np.ones((len(keep), kp.shape[1]), bool))
        edge_std = self.box_noise_fraction * (true_box[:, 3] - true_box[:, 1])
        true_box = true_box + rng.normal(size=true_box.shape) * edge_std[:, None]
        true_box = np.column_stack([np.minimum(true_box[:, :2], true_box[:, 2:]),
                                    np.maximum(true_box[:, :2], true_box[:, 2:])])
        boxes = np.concatenate([true_box, boxes_from_keypoints(fp_kp, fp_conf >= self.box_min_confidence)])
        return Detections(keypoints[order], confidences[order], np.clip(boxes[order], 0.0, [w - 1.0, h - 1.0] * 2))

    def _person_offsets(self, scene: str, ids: np.ndarray, height_px: np.ndarray) -> np.ndarray:
        """(N, 1, 2) pixel offsets of persons ``ids`` (N,) whose keypoints span ``height_px`` (N,)."""
        if self.person_offset_u == 0.0 and self.person_offset_v == 0.0:
            return np.zeros((len(ids), 1, 2))
        crc = zlib.crc32(scene.encode())
        unit = np.array([np.random.default_rng([self.seed & 0xFFFFFFFF, crc, int(i) & 0xFFFFFFFF, 1]).normal(size=2)
                         for i in ids]).reshape(-1, 2)
        return (unit * [self.person_offset_u, self.person_offset_v] * np.asarray(height_px)[:, None])[:, None, :]

    def _false_positives(self, rng: np.random.Generator, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """Small skeleton-shaped ghosts near the horizon: (F, 17, 2) pixels, (F, 17) confidences."""
        count = rng.poisson(self.false_positives_per_frame)
        if count == 0:
            return np.zeros((0, 17, 2)), np.zeros((0, 17))
        # a standing person seen from the front, in units of body height: u right, v down from the feet
        template = -body_keypoints(np.ones(1), np.zeros(1), np.zeros(1), np.zeros((1, 2)))[0][:, [1, 2]]
        size = rng.uniform(12.0, 40.0, count)
        feet = np.stack([rng.uniform(0.0, width, count), rng.uniform(0.5 * height, 0.5 * height + 60.0, count)], axis=1)
        kp = (
            feet[:, None, :]
            + template[None] * size[:, None, None]
            + rng.normal(0.0, 0.1, (count, 17, 2)) * size[:, None, None]
        )
        return np.clip(kp, 0.0, [width - 1.0, height - 1.0]), rng.uniform(0.1, 0.45, (count, 17))
