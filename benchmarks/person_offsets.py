"""How far a detected skeleton sits from the person's true ground point, person by person.

Frame-to-frame jitter (``fit_detector_model.py``) is only the part of the keypoint error that
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
the synthetic side); ``fit_detector_model.py --person-offsets`` records everything.
"""

from __future__ import annotations

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

    def add(acc, det, boxes, uv, counted, key_of):
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
        ped = cam.pedestrians
        bottom = ped.centers_cam + np.column_stack([np.zeros(len(ped)), ped.sizes_wlh[:, 2] / 2, np.zeros(len(ped))])
        uv = bottom @ cam.K.T
        add(truth3d, dets[f"nuscenes/{cam.camera}"], ped.boxes, uv[:, :2] / uv[:, 2:3], np.ones(len(ped), bool),
            lambda g, c=cam.camera: ("nuscenes", c, g))
    for folder in mot17.sequence_folders(samples / "mot17"):
        seq = mot17.read_sequence(folder)
        for f in seq.frames:
            gt = seq.pedestrians.in_frame(f)
            uv = np.column_stack([(gt.boxes[:, 0] + gt.boxes[:, 2]) / 2, gt.boxes[:, 3]])
            add(boxes2d, dets[f"mot17/{folder.name}/{f}"], gt.boxes, uv, gt.visibility >= 0.8,
                lambda g, n=folder.name, ids=gt.ids: ("mot17", n, int(ids[g])))
    return truth3d, boxes2d
