"""Named parameter sets of the detector model (:class:`pedenv.synthetic.detector.DetectorModel`).

``default``: the hand-set model the synthetic benchmarks were built with (50 % detection at
25 px keypoint extent, 98 % above 80 px), kinder than any real network at small sizes.

``yolo11n-pose-single``: fitted to YOLO11n-pose (onnx backend, score > 0.25) in one
whole-frame pass at today's default input (:func:`pedenv.pose.models.choose_input_size`:
384x640 for frames at least 16:10 wide, else 640x640) on the real samples (MOT17,
KITTI tracking and object, nuScenes cameras) by ``benchmarks/fit_detector_model.py``; the
measured tables are ``benchmarks/results/detector_yolo11n-pose-single.json`` and a test
checks that these values reproduce its recall by height within 10 points. Heights here are
the keypoint extent, which is 0.816 of a real annotated box (head top to soles). The
network in that mode finds almost nobody below 150 px box height (50 % at 220 px). Its
keypoint noise is the frame-to-frame jitter on MOT17 (measured above 100 px box height only;
the power law below is extrapolated); jitter between near-identical consecutive frames is a
lower bound of the error against the truth. False positives: MOT17 and KITTI frames.

``yolo11n-pose-fast``: the onnx backend's ``fast`` detection mode (one pass, the input
fitted to the frame's aspect), measured the same way: as blind as the single pass
(recall 0 / 0 / 6 / 72 % in the bins <50, 50-100, 100-200, >=200 px).

``yolo11n-pose-far``: the ``far`` mode (:mod:`pedenv.detection.levels`: a pyramid of the whole
frame and x1, x2 levels over the rows where people of each level's heights stand):
recall 5 / 70 / 87 / 99 % in the bins <50, 50-100, 100-200, >=200 px, 0.31 false positives
per frame. Its recall rises steeply at the finest level's smallest person and then flattens,
which a per-person logistic fit misses by up to 19 points in a bin; the curve here is fitted
to the recall table as the synthetic scenes see it (``fit_detector_model.py
--fit-recall-table``: 50 % at 47 px keypoint extent, i.e. 58 px box height; largest bin gap
9 points: 14 / 63 / 96 / 99 %). Each person's skeleton is also offset, the same in every
frame, by what the real network showed against the KITTI and nuScenes 3D truth beyond the
synthetic skeletons' own spread (``--person-offsets``: across persons 3.5 % of the box
height sideways and 2.3 % vertically, the synthetic skeletons alone 1.1 / 1.2 %). The other
profiles have no such offset (not measured for their modes).

``yolo11n-pose-far-kitti``: ``yolo11n-pose-far`` with its false positives per image area on a
KITTI frame: the fit counted 15 over 33 MOT17 frames of 1920x1080, 6 of 640x480 and 9 KITTI
frames of 1242x375 (none on KITTI), 0.20 per megapixel pooled, so 0.094 on a 1242x375 frame
(:data:`FAR_FALSE_POSITIVES_PER_MEGAPIXEL`); the per-frame 0.31 is MOT17's larger frames. As the
fit counted them, none lies at least half inside a person (``false_positives_outside_people``).
The default of the whole KITTI drives (:mod:`pedenv.datasets.kitti_drives`).

``yolo11n-pose-native``: the same network over the whole frame at the frame's own
resolution (sides rounded up to 32 px; a dynamic-input ONNX export), the reference for the
tiled ``far`` detection mode: 50 % at 109 px box height, 85 % of persons 100-200 px tall
found. Tables: ``benchmarks/results/detector_yolo11n-pose-native.json``.

False positives: detections lying mostly outside every annotated person and ignore region
(MOT17's amodal boxes would otherwise count half-hidden people found as false).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from types import MappingProxyType

from pedenv.errors import InputError
from pedenv.validation import check_number

DEFAULT_PROFILE = "default"

#: False positives of ``yolo11n-pose-far`` per megapixel of frame: the 15 the fit counted
#: (``benchmarks/results/detector_yolo11n-pose-far.json``) over the 74.5 megapixels of its 48
#: frames (33 MOT17 frames of 1920x1080, 6 of 640x480, 9 KITTI frames of 1242x375).
FAR_FALSE_POSITIVES_PER_MEGAPIXEL = 15 / (33 * 1920 * 1080 + 6 * 640 * 480 + 9 * 1242 * 375) * 1e6

_DEFAULT = {"noise_px_large": 1.5, "noise_px_small": 3.5, "extremity_noise_factor": 1.3, "unseen_noise_factor": 3.0,
            "half_detection_height_px": 25.0, "detection_slope_px": 14.0, "false_positives_per_frame": 0.05,
            "box_noise_fraction": 0.03, "box_min_confidence": 0.3, "person_offset_u": 0.0, "person_offset_v": 0.0,
            "unseen_detection": 1.0, "false_positives_outside_people": 0.0}

_FAR = {**_DEFAULT,
        "half_detection_height_px": 47.0, "detection_slope_px": 11.0, "false_positives_per_frame": 0.3125,
        "noise_px_small": 0.356, "noise_px_large": 0.665, "person_offset_u": 0.0336, "person_offset_v": 0.0196,
        "unseen_detection": 0.0}

#: Profile name -> parameter values (read-only).
PROFILES = MappingProxyType({
    "default": MappingProxyType(_DEFAULT),
    "yolo11n-pose-single": MappingProxyType({
        **_DEFAULT,
        "half_detection_height_px": 180.0, "detection_slope_px": 15.3, "false_positives_per_frame": 0.042,
        "noise_px_small": 0.085, "noise_px_large": 0.87}),
    "yolo11n-pose-fast": MappingProxyType({
        **_DEFAULT,
        "half_detection_height_px": 179.5, "detection_slope_px": 14.5, "false_positives_per_frame": 0.042,
        "noise_px_small": 0.22, "noise_px_large": 0.84}),
    "yolo11n-pose-far": MappingProxyType(_FAR),
    "yolo11n-pose-far-kitti": MappingProxyType({
        **_FAR, "false_positives_per_frame": round(FAR_FALSE_POSITIVES_PER_MEGAPIXEL * 1242 * 375 * 1e-6, 4),
        "false_positives_outside_people": 1.0}),
    "yolo11n-pose-native": MappingProxyType({
        **_DEFAULT,
        "half_detection_height_px": 88.7, "detection_slope_px": 12.4, "false_positives_per_frame": 0.125,
        "noise_px_small": 0.175, "noise_px_large": 0.83}),
})


def profile_parameters(name: str) -> dict[str, float]:
    """The parameter values of profile ``name``; InputError naming the valid profiles."""
    if name not in PROFILES:
        raise InputError(f"unknown detector-model profile {name!r}; valid: {', '.join(PROFILES)}")
    return dict(PROFILES[name])


#: Parameter -> its accepted range (low, high).
_RANGES = {"noise_px_large": (0.0, 50.0), "noise_px_small": (0.0, 50.0), "extremity_noise_factor": (1.0, 10.0),
           "unseen_noise_factor": (1.0, 20.0), "half_detection_height_px": (0.0, 1000.0),
           "detection_slope_px": (0.1, 500.0), "false_positives_per_frame": (0.0, 20.0),
           "box_noise_fraction": (0.0, 1.0), "box_min_confidence": (0.0, 1.0), "person_offset_u": (0.0, 0.5),
           "person_offset_v": (0.0, 0.5), "unseen_detection": (0.0, 1.0), "false_positives_outside_people": (0.0, 1.0)}


@dataclass(frozen=True)
class DetectorParameters:
    """The numbers of the detector model (:class:`~pedenv.synthetic.detector.DetectorModel`), each
    checked against its range (in brackets).

    noise_px_large: keypoint noise standard deviation (px) for a 300 px tall person [0, 50].
    noise_px_small: the same for a 30 px tall person [0, 50]. Raising either makes every
        position estimate noisier; the noise follows a power law in between and beyond.
    extremity_noise_factor: wrists and ankles get this times more noise [1, 10].
    unseen_noise_factor: keypoints the camera does not see get this times more noise [1, 20].
    half_detection_height_px: pixel height at which half of the persons are detected [0, 1000].
        Raising it misses more distant pedestrians.
    detection_slope_px: width of the logistic detection curve in pixels [0.1, 500]; the
        default puts 98 % detection at about 80 px.
    false_positives_per_frame: mean number of spurious skeletons per frame (Poisson) [0, 20].
    box_noise_fraction: standard deviation of each edge of a detected person's box, as a
        share of its height [0, 1] (the box comes from the network's box head, not from the
        noisy keypoints). Raising it makes boxes, and so the association, less precise.
    box_min_confidence: a false positive's box spans its keypoints at least this confident [0, 1].
    person_offset_u, person_offset_v: standard deviations of each person's persistent
        skeleton offset, sideways and vertical, as shares of the person's keypoint extent
        [0, 0.5] (0 in the hand-set profile). Raising them makes each track's bias, which no
        filter averages away, larger.
    unseen_detection: the detection probability of a person none of whose keypoints is seen (wholly
        hidden) relative to a visible one of that size [0, 1]: 1 in the hand-set profile (its
        guesses), 0 in ``yolo11n-pose-far`` (a network finds nobody it cannot see; the renderer
        from labels, :mod:`pedenv.synthetic.labelled`, hides the persons an occlusion flag misses).
    false_positives_outside_people: 1 draws a false positive that lies at least half inside a
        person's box again elsewhere, as the fit counted them (a detection mostly inside a person
        was not counted false); 0 places them anywhere in their band of rows (the other profiles,
        as they were measured with) [0, 1].
    """

    noise_px_large: float
    noise_px_small: float
    extremity_noise_factor: float
    unseen_noise_factor: float
    half_detection_height_px: float
    detection_slope_px: float
    false_positives_per_frame: float
    box_noise_fraction: float
    box_min_confidence: float
    person_offset_u: float
    person_offset_v: float
    unseen_detection: float
    false_positives_outside_people: float

    def __post_init__(self) -> None:
        for name, (low, high) in _RANGES.items():
            object.__setattr__(self, name, float(check_number(f"DetectorModel {name}", getattr(self, name), low, high)))

    @classmethod
    def of(cls, profile: str, overrides: dict[str, float | None]) -> DetectorParameters:
        """Profile ``profile``'s values with ``overrides`` set (None entries keep the profile's)."""
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(overrides) - names)
        if unknown:
            raise InputError(f"unknown detector-model option(s) {', '.join(unknown)}; valid: seed, profile, "
                             f"{', '.join(sorted(names))}")
        return replace(cls(**profile_parameters(profile)), **{k: v for k, v in overrides.items() if v is not None})
