"""How far a detected skeleton sits from the person's true ground point, person by person.

Frame-to-frame jitter (``benchmarks/fit_detector_model.py``) is only the part of the keypoint error that
changes between frames. A network also places one person's skeleton consistently off: the
ankles above or below the soles, the body's centre column to one side. That persistent part
does not average out in a track, and it sets the fused method's per-person bias.

Measured here, per matched detection (score > 0.25, IoU >= 0.5 with a person annotated as
mostly visible; ankles and hips at keypoint confidence >= 0.3), in units of the annotated
box height h:

* ``foot``: the mean ankle row minus the row of the person's true ground point;
* ``column``: the mean column of hips and ankles minus the ground point's column.

Real: KITTI tracking and object samples and the five nuScenes cameras, the ground point
being the bottom centre of the annotated 3D box projected with the sample's calibration.
Each person's offsets are the median over their frames; the spread across persons (robust
std, 1.4826 MAD) is the persistent offset. MOT17 (2D boxes only: box bottom and centre
column) is a cross-check on more persons. Synthetic: the same on the built-in scenes with
the detector model, the ground point being the true position projected. The detector
model's ``person_offset_u`` / ``person_offset_v`` are what the synthetic skeletons lack:
``sqrt(real**2 - synthetic**2)``, converted from box heights to keypoint extents. The
measuring and the fit live in :mod:`pedenv.synthetic.detector_fit` (the profile test reruns
the synthetic side); ``benchmarks/fit_detector_model.py --person-offsets`` records everything.

:func:`ankle_heights` measures, in metres, how high the network's lower ankle keypoint (the one
the ground cue cuts with the ground) sits above the ground under the person: the bottom of
the annotated 3D box, in the camera frame (y down) at the box's depth ``z``,
``y_bottom - (v_ankle - c_y) z / f_y``. Per person the median over their frames, then the
median and quartiles across persons, for KITTI (tracking and object samples) and nuScenes
apart; the ground cue's ``fused.ankle_keypoint_offset_m`` is the KITTI median minus the
anatomical ankle height (0.046 x 1.72 m). The spread across persons (``robust_std_m``, 1.4826
MAD) of KITTI and nuScenes together, people and cameras apart, is the static ground cue's
``fused.ankle_keypoint_offset_std_m``: how far one person's ankle keypoint may sit off that offset.
The detections are the cache of ``benchmarks/real_detections.py``::

    PYTHONPATH=src python benchmarks/real_detections.py --mode far --min-score 0.25 \\
        --only kitti,nuscenes --out det-far.npz
    PYTHONPATH=src python benchmarks/ankle_heights.py --detections det-far.npz
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from pedenv.synthetic.detector_fit import Offsets


def _project(P: np.ndarray, points: np.ndarray) -> np.ndarray:
    x = np.column_stack([points, np.ones(len(points))]) @ P.T
    return x[:, :2] / x[:, 2:3]


def real_offsets(samples: Path, dets: dict) -> tuple[Offsets, Offsets]:
    """(against the 3D truth: KITTI and nuScenes, against MOT17's boxes) over the cached detections."""
    from pedenv.datasets import kitti_files as kitti
    from pedenv.datasets import mot17, nuscenes_cameras

    def add(acc: Offsets, det: dict, boxes: np.ndarray, uv: np.ndarray, counted: np.ndarray,
            key_of: Callable) -> None:
        acc.add(key_of, det["keypoints"], det["confidences"], det["scores"], det["boxes"], boxes, uv, counted)

    truth3d, boxes2d = Offsets(), Offsets()
    training = samples / "kitti" / "tracking_mini" / "training"
    for name in kitti.tracking_sequence_names(training):
        seq = kitti.read_tracking_sequence(training, name)
        for f in seq.frames:
            ped = seq.labels.in_frame(f).of_type("Pedestrian")
            add(truth3d, dets[f"kitti/{name}/{f}"], ped.boxes, _project(seq.calib.P2, ped.locations),
                ped.occluded <= 1, lambda g, n=name, ids=ped.track_id: ("kitti", n, int(ids[g])))
    obj = samples / "kitti" / "object_samples" / "training"
    for p in sorted((obj / "image_2").glob("*.png")):
        ped = kitti.read_labels(obj / "label_2" / f"{p.stem}.txt").of_type("Pedestrian")
        calib = kitti.read_calib(obj / "calib" / f"{p.stem}.txt")
        add(truth3d, dets[f"kitti-object/{p.stem}"], ped.boxes, _project(calib.P2, ped.locations), ped.occluded <= 1,
            lambda g, s=p.stem: ("kitti-object", s, g))
    for cam in nuscenes_cameras.read_cameras(samples / "nuscenes-0061"):
        nped = cam.pedestrians
        zeros = np.zeros(len(nped))
        bottom = nped.centers_cam + np.column_stack([zeros, nped.sizes_wlh[:, 2] / 2, zeros])
        uv = bottom @ cam.K.T
        add(truth3d, dets[f"nuscenes/{cam.camera}"], nped.boxes, uv[:, :2] / uv[:, 2:3], np.ones(len(nped), bool),
            lambda g, c=cam.camera: ("nuscenes", c, g))
    for folder in mot17.sequence_folders(samples / "mot17"):
        mseq = mot17.read_sequence(folder)
        for f in mseq.frames:
            gt = mseq.pedestrians.in_frame(f)
            uv = np.column_stack([(gt.boxes[:, 0] + gt.boxes[:, 2]) / 2, gt.boxes[:, 3]])
            add(boxes2d, dets[f"mot17/{folder.name}/{f}"], gt.boxes, uv, gt.visibility >= 0.8,
                lambda g, n=folder.name, ids=gt.ids: ("mot17", n, int(ids[g])))
    return truth3d, boxes2d


#: A matched person counts when both ankle keypoints are at least this confident (the
#: ground cue needs a stance ankle it can trust; a guessed ankle would measure the guess).
ANKLE_CONFIDENCE = 0.5


def lower_ankle_heights(det: dict, truth_boxes: np.ndarray, bottoms_cam: np.ndarray, K: np.ndarray,
                        counted: np.ndarray) -> dict[int, float]:
    """Truth index -> metres the matched detection's lower ankle keypoint lies above the truth's
    3D box bottom. det: one image's cached detections; truth_boxes (M, 4) px; bottoms_cam
    (M, 3) the boxes' bottom centres, camera frame (y down), metres; K (3, 3) px; counted (M,) bool."""
    from pedenv.boxes import greedy_match, iou_matrix
    from pedenv.synthetic.detector_fit import ANKLES, SCORE

    keep = np.asarray(det["scores"]) > SCORE
    kp, cf = np.asarray(det["keypoints"])[keep], np.asarray(det["confidences"])[keep]
    truth = np.asarray(truth_boxes, float).reshape(-1, 4)
    out = {}
    for d, g in greedy_match(iou_matrix(np.asarray(det["boxes"])[keep], truth), np.asarray(det["scores"])[keep], 0.5):
        if counted[g] and (cf[d, ANKLES] >= ANKLE_CONFIDENCE).all():
            v = float(kp[d, ANKLES, 1].max())  # the lower ankle: the larger image row
            z = float(bottoms_cam[g, 2])
            out[int(g)] = float(bottoms_cam[g, 1] - (v - K[1, 2]) * z / K[1, 1])
    return out


def ankle_heights(samples: Path, dets: dict) -> dict[str, list[float]]:
    """Per dataset (``kitti``, ``nuscenes``) each person's median lower-ankle height above the
    ground under them, metres (module notes), over the cached detections ``dets``."""
    from pedenv.datasets import kitti_files as kitti
    from pedenv.datasets import nuscenes_cameras

    per: dict[tuple, list[float]] = {}
    training = samples / "kitti" / "tracking_mini" / "training"
    for name in kitti.tracking_sequence_names(training):
        seq = kitti.read_tracking_sequence(training, name)
        for f in seq.frames:
            ped = seq.labels.in_frame(f).of_type("Pedestrian")
            found = lower_ankle_heights(dets[f"kitti/{name}/{f}"], ped.boxes, ped.locations, seq.calib.P2[:, :3],
                                        ped.occluded <= 1)
            for g, h in found.items():
                per.setdefault(("kitti", name, int(ped.track_id[g])), []).append(h)
    obj = samples / "kitti" / "object_samples" / "training"
    for p in sorted((obj / "image_2").glob("*.png")):
        ped = kitti.read_labels(obj / "label_2" / f"{p.stem}.txt").of_type("Pedestrian")
        calib = kitti.read_calib(obj / "calib" / f"{p.stem}.txt")
        for g, h in lower_ankle_heights(dets[f"kitti-object/{p.stem}"], ped.boxes, ped.locations, calib.P2[:, :3],
                                        ped.occluded <= 1).items():
            per.setdefault(("kitti", p.stem, g), []).append(h)
    nuscenes = samples / "nuscenes-0061"  # when the cache holds its cameras
    for cam in nuscenes_cameras.read_cameras(nuscenes) if any(k.startswith("nuscenes/") for k in dets) else []:
        nped = cam.pedestrians
        bottoms = nped.centers_cam + np.column_stack([np.zeros(len(nped)), nped.sizes_wlh[:, 2] / 2,
                                                      np.zeros(len(nped))])
        for g, h in lower_ankle_heights(dets[f"nuscenes/{cam.camera}"], nped.boxes, bottoms, cam.K,
                                        np.ones(len(nped), bool)).items():
            per.setdefault(("nuscenes", cam.camera, g), []).append(h)
    out: dict[str, list[float]] = {"kitti": [], "nuscenes": []}
    for key, heights in per.items():
        out[key[0]].append(float(np.median(heights)))
    return out
