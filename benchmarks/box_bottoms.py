"""Where a 2D box's bottom edge puts a person against their 3D truth, on KITTI (not MOT17).

    PYTHONPATH=src python benchmarks/box_bottoms.py --detections DET.npz [--samples ../shared/samples/real]

MOT17's static-camera truth is a 2D box's bottom centre cut with the ground; the ground cue
estimates the person's ground point from the ankle. KITTI has both a human-drawn 2D box and a 3D
box per pedestrian, so the two conventions can be compared there without MOT17: per pedestrian
matched by the real network (``DET.npz`` from ``real_detections.py --mode far --min-score 0.25``;
box IoU >= 0.5; occluded <= 1, not truncated, the box's bottom inside the image), each cut with the
plane of the 3D box's bottom face (camera frame, y down), as depth ``z`` against the 3D box's
bottom-face centre (metres; negative: nearer the camera):

* ``truth``: the KITTI 2D box's bottom centre (the MOT17-style truth point);
* ``net``: the network's box's bottom centre;
* ``ankle``: the network's lower ankle cut with the plane lifted by the ground cue's
  ``ankle_height`` (the ground cue alone, with a single ankle);

and ``gap`` px: the KITTI box's bottom row minus the network's (positive: the truth box reaches lower);
``a_net``: metres, the lower ankle's ray's height above the ground where it passes over the network
box bottom's cut (``static_feet.py``'s ``a_net``, there on MOT17).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: Ankle keypoints (COCO) and the confidence a seen ankle needs (the fused cues' default).
ANKLES = [15, 16]
ANKLE_CONFIDENCE = 0.3
#: The medians are also given for the people up to this depth (metres; MOT17-02's and -09's near
#: people stand 7-10 m from cameras 1.1-1.7 m up, KITTI's 1.65 m) and beyond it.
NEAR_M = 12.0
#: A box whose bottom lies this close (px) to the image's bottom edge may be cut by it.
EDGE_PX = 2.0


def cut_depth(K: np.ndarray, pixel: np.ndarray, plane_y: float) -> float:
    """Depth z (metres) where the ray of ``pixel`` (2,) px meets the plane y = ``plane_y`` (camera
    frame, y down: a plane ``plane_y`` metres below the camera centre); inf above the horizon."""
    ray = np.linalg.inv(K) @ np.array([pixel[0], pixel[1], 1.0])
    return float(plane_y / ray[1]) if ray[1] > 1e-9 else float("inf")


def person_rows(det: dict, labels, K: np.ndarray, height: int, lift: float) -> list[tuple]:
    """(depth z, truth, net, ankle, gap, a_net) per counted pedestrian of one image (module notes).
    det: the image's cached detections; labels: its KITTI Pedestrian labels; K (3, 3) px."""
    from pedenv.boxes import greedy_match, iou_matrix

    boxes, kp, cf = np.asarray(det["boxes"]), np.asarray(det["keypoints"]), np.asarray(det["confidences"])
    rows: list[tuple] = []
    pairs = greedy_match(iou_matrix(boxes, labels.boxes), np.asarray(det["scores"]), 0.5)
    for d, g in pairs:
        box, loc = labels.boxes[g], labels.locations[g]
        if labels.occluded[g] > 1 or labels.truncated[g] > 0 or box[3] >= height - 1 - EDGE_PX:
            continue
        z, y = float(loc[2]), float(loc[1])
        truth = cut_depth(K, np.array([0.5 * (box[0] + box[2]), box[3]]), y) - z
        net = cut_depth(K, np.array([0.5 * (boxes[d, 0] + boxes[d, 2]), boxes[d, 3]]), y) - z
        seen = [k for k in ANKLES if cf[d, k] >= ANKLE_CONFIDENCE]
        ankle, a_net = np.nan, np.nan
        if seen:
            uv = kp[d, max(seen, key=lambda k: kp[d, k, 1])]
            ankle = cut_depth(K, uv, y - lift) - z
            ray = np.linalg.inv(K) @ np.array([uv[0], uv[1], 1.0])
            a_net = y - ray[1] / ray[2] * (z + net)  # the ankle ray's height over the network box bottom's cut
        rows.append((z, truth, net, ankle, box[3] - boxes[d, 3], a_net))
    return rows


def kitti_rows(samples: Path, dets: dict, lift: float) -> np.ndarray:
    """(N, 6) rows (:func:`person_rows`) over the KITTI tracking and object samples."""
    from pedenv.datasets import kitti_files as kitti
    from pedenv.images import image_size

    rows: list[tuple] = []
    training = samples / "kitti" / "tracking_mini" / "training"
    for name in kitti.tracking_sequence_names(training):
        seq = kitti.read_tracking_sequence(training, name)
        for f in seq.frames:
            height = image_size(seq.image_path(f))[1]
            rows += person_rows(dets[f"kitti/{name}/{f}"], seq.labels.in_frame(f).of_type("Pedestrian"),
                                seq.calib.P2[:, :3], height, lift)
    obj = samples / "kitti" / "object_samples" / "training"
    for p in sorted((obj / "image_2").glob("*.png")):
        calib = kitti.read_calib(obj / "calib" / f"{p.stem}.txt")
        labels = kitti.read_labels(obj / "label_2" / f"{p.stem}.txt").of_type("Pedestrian")
        rows += person_rows(dets[f"kitti-object/{p.stem}"], labels, calib.P2[:, :3], image_size(p)[1], lift)
    return np.array(rows, float).reshape(-1, 6)


def main(argv: list[str] | None = None) -> int:
    from pedenv.config import Config
    from pedenv.localization import configure
    from pedenv.localization.fused.ground import ankle_height

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=ROOT.parent / "shared" / "samples" / "real")
    parser.add_argument("--detections", type=Path, required=True, help="cache written by real_detections.py")
    args = parser.parse_args(argv)
    from fit_detector_model import load

    dets = load(args.detections)
    lift = ankle_height(configure(Config(), "fused").fused)
    rows = kitti_rows(args.samples, dets, lift)
    print(f"KITTI pedestrians ({len(rows)}): depth, metres against the 3D box's bottom-face centre "
          f"(negative: nearer); gap px (the KITTI box's bottom below the network's); ankle lift {lift:.3f} m")
    print("| depth m | truth (2D box bottom) | net (network's box bottom) | ankle (ground cue) | gap px | a_net m |")
    print("|---|---|---|---|---|---|")
    for row in rows[np.argsort(rows[:, 0])]:
        print("| " + " | ".join(f"{x:+.3f}" if k else f"{x:.1f}" for k, x in enumerate(row[:4]))
              + f" | {row[4]:+.1f} | {row[5]:.3f} |")
    for label, sel in (("all", rows[:, 0] > 0), (f"<= {NEAR_M:.0f} m", rows[:, 0] <= NEAR_M),
                       (f"> {NEAR_M:.0f} m", rows[:, 0] > NEAR_M)):
        med = np.nanmedian(rows[sel], axis=0)
        print(f"| median, {label} ({sel.sum()}) | {med[1]:+.3f} | {med[2]:+.3f} | {med[3]:+.3f} | "
              f"{med[4]:+.1f} | {med[5]:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
