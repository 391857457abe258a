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
* a few small skeleton-shaped false positives appear (``false_positives_per_frame``), anywhere in
  a band of rows below the middle or, with ``false_positives_outside_people``, outside the people;
* a person none of whose keypoints is seen is detected ``unseen_detection`` times as often.

The numbers come from a named profile (:mod:`pedenv.synthetic.detector_profiles`): the
hand-set ``default``, or values fitted to a real network on real images.

Random numbers depend only on ``(seed, scene name, frame index)``, a person's offset only on
``(seed, scene name, person id)``: reruns reproduce.
"""

from __future__ import annotations

import zlib

import numpy as np

from pedenv.boxes import containment_matrix
from pedenv.errors import InputError
from pedenv.records import Detections, Frame, PredictedTracks, boxes_from_keypoints
from pedenv.skeleton import CocoKeypoint as KP
from pedenv.synthetic.detector_profiles import DEFAULT_PROFILE, PROFILES, DetectorParameters
from pedenv.synthetic.walker import body_keypoints

__all__ = ["DEFAULT_PROFILE", "PROFILES", "DetectorModel", "DetectorParameters"]

#: Times a false positive lying in a person is drawn again before it is dropped
#: (``false_positives_outside_people``): a ghost lands in a person about one time in ten on
#: KITTI's busiest drive, so three redraws keep all but about one in a thousand.
GHOST_REDRAWS = 3

_EXTREMITIES = np.array([KP.LEFT_WRIST, KP.RIGHT_WRIST, KP.LEFT_ANKLE, KP.RIGHT_ANKLE])
_FACE = np.array([KP.NOSE, KP.LEFT_EYE, KP.RIGHT_EYE, KP.LEFT_EAR, KP.RIGHT_EAR])


class DetectorModel:
    """The ``detector-model`` pose backend: detections simulated from ground-truth skeletons.

    seed: random seed (with the scene name and frame index it fixes every draw).
    profile: a named set of parameters (:data:`PROFILES`): ``default`` (the hand-set model), or
        one fitted to a real network, e.g. ``yolo11n-pose-single``.
    overrides: parameters given explicitly (:class:`~pedenv.synthetic.detector_profiles.DetectorParameters`:
        ``noise_px_large``, ``half_detection_height_px``, ``person_offset_u`` ...) override the
        profile's; each is also readable as an attribute (``model.half_detection_height_px``).
    """

    name = "detector-model"

    def __init__(self, seed: int = 0, *, profile: str | None = None, **overrides: float | None) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise InputError(f"DetectorModel seed must be an integer, got {seed!r}")
        self.seed = int(seed)
        self.profile = profile or DEFAULT_PROFILE
        self.parameters = DetectorParameters.of(self.profile, overrides)

    def __getattr__(self, name: str) -> float:
        """A parameter's value (``model.noise_px_large``), from :attr:`parameters`."""
        if name != "parameters" and name in DetectorParameters.__dataclass_fields__:
            return getattr(self.parameters, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def noise_std_px(self, height_px: np.ndarray) -> np.ndarray:
        """Keypoint noise standard deviation (px) of persons ``height_px`` (N,) pixels tall."""
        p = self.parameters
        if p.noise_px_large == 0.0 or p.noise_px_small == 0.0:
            return np.interp(height_px, [30.0, 300.0], [p.noise_px_small, p.noise_px_large])
        exponent = np.log(p.noise_px_small / p.noise_px_large) / np.log(30.0 / 300.0)
        return p.noise_px_large * (np.clip(height_px, 5.0, 2000.0) / 300.0) ** exponent

    def detection_probability(self, height_px: np.ndarray) -> np.ndarray:
        """Probability (N,) that persons ``height_px`` (N,) pixels tall are detected."""
        p = self.parameters
        return 1.0 / (
            1.0 + np.exp(-(np.asarray(height_px, float) - p.half_detection_height_px) / p.detection_slope_px)
        )

    def __call__(self, frame: Frame, tracks: PredictedTracks | None = None) -> Detections:  # noqa: ARG002 - sees no tracks
        p = self.parameters
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
        hidden = ~seen.any(axis=1) if n else np.zeros(0, bool)  # wholly hidden persons
        detected = rng.random(n) < self.detection_probability(height) * np.where(hidden, p.unseen_detection, 1.0)

        sigma = np.repeat(self.noise_std_px(height)[:, None], kp.shape[1], axis=1)
        sigma[:, _EXTREMITIES] *= p.extremity_noise_factor
        sigma = np.where(seen, sigma, p.unseen_noise_factor * sigma + 0.03 * height[:, None])
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
        people = (boxes_from_keypoints(kp, np.ones(kp.shape[:2], bool))
                  if p.false_positives_outside_people and n else np.zeros((0, 4)))
        fp_kp, fp_conf = self._false_positives(rng, w, h, people)
        keypoints = np.concatenate([noisy[keep], fp_kp])
        confidences = np.concatenate([conf[keep], fp_conf])
        order = rng.permutation(keypoints.shape[0])  # networks report persons in no particular order
        # A one-stage network regresses the person's box in its own head: the true box with
        # edges off by a share of the height, not the hull of the noisy keypoints.
        true_box = boxes_from_keypoints(kp[keep], np.ones((len(keep), kp.shape[1]), bool))
        edge_std = p.box_noise_fraction * (true_box[:, 3] - true_box[:, 1])
        true_box = true_box + rng.normal(size=true_box.shape) * edge_std[:, None]
        true_box = np.column_stack([np.minimum(true_box[:, :2], true_box[:, 2:]),
                                    np.maximum(true_box[:, :2], true_box[:, 2:])])
        boxes = np.concatenate([true_box, boxes_from_keypoints(fp_kp, fp_conf >= p.box_min_confidence)])
        return Detections(keypoints[order], confidences[order], np.clip(boxes[order], 0.0, [w - 1.0, h - 1.0] * 2))

    def _person_offsets(self, scene: str, ids: np.ndarray, height_px: np.ndarray) -> np.ndarray:
        """(N, 1, 2) pixel offsets of persons ``ids`` (N,) whose keypoints span ``height_px`` (N,)."""
        p = self.parameters
        if p.person_offset_u == 0.0 and p.person_offset_v == 0.0:
            return np.zeros((len(ids), 1, 2))
        crc = zlib.crc32(scene.encode())
        unit = np.array([np.random.default_rng([self.seed & 0xFFFFFFFF, crc, int(i) & 0xFFFFFFFF, 1]).normal(size=2)
                         for i in ids]).reshape(-1, 2)
        return (unit * [p.person_offset_u, p.person_offset_v] * np.asarray(height_px)[:, None])[:, None, :]

    def _false_positives(self, rng: np.random.Generator, width: int, height: int,
                         people: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Small skeleton-shaped ghosts near the horizon: (F, 17, 2) pixels, (F, 17) confidences.
        A ghost lying at least half inside one of the ``people`` boxes (P, 4) is drawn again
        (:data:`GHOST_REDRAWS` times at most, then dropped)."""
        count = rng.poisson(self.parameters.false_positives_per_frame)
        if count == 0:
            return np.zeros((0, 17, 2)), np.zeros((0, 17))
        kp, conf = self._ghosts(rng, count, width, height)
        if len(people) == 0:
            return kp, conf
        for _ in range(GHOST_REDRAWS):
            inside = self._in_people(kp, conf, people)
            if not inside.any():
                return kp, conf
            kp[inside], conf[inside] = self._ghosts(rng, int(inside.sum()), width, height)
        keep = ~self._in_people(kp, conf, people)
        return kp[keep], conf[keep]

    def _in_people(self, kp: np.ndarray, conf: np.ndarray, people: np.ndarray) -> np.ndarray:
        """(F,) whether each ghost's box (as reported) lies at least half inside one of ``people`` (P, 4)."""
        boxes = boxes_from_keypoints(kp, conf >= self.parameters.box_min_confidence)
        return containment_matrix(boxes, people).max(1) >= 0.5

    def _ghosts(self, rng: np.random.Generator, count: int, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
        """``count`` ghosts anywhere in the band of rows: (count, 17, 2) pixels, (count, 17) confidences."""
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
