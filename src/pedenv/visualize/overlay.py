"""Drawing on camera images: skeletons, boxes, track ids and distance labels.

All images are (H, W, 3) uint8 RGB; drawing returns a new image. Pixel arrays are in
the image's own pixels (u right, v down).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import cv2
import numpy as np

from pedenv.records import Detections, Frame
from pedenv.skeleton import COCO_BONES
from pedenv.state import EnvironmentState

#: An RGB colour, 0-255 per channel.
Color = tuple[int, int, int]
#: Keypoints at or below this confidence are not drawn.
MIN_DRAW_CONFIDENCE = 0.3
_PALETTE = np.array([[230, 25, 75], [60, 180, 75], [0, 130, 200], [245, 130, 48], [145, 30, 180],
                     [70, 240, 240], [240, 50, 230], [210, 245, 60], [250, 190, 212], [0, 128, 128],
                     [220, 190, 255], [170, 110, 40], [128, 0, 0], [170, 255, 195], [128, 128, 0]])


def color_for(key: int) -> tuple[int, int, int]:
    """A stable RGB colour per track id (or detection index)."""
    r, g, b = (int(c) for c in _PALETTE[int(key) % len(_PALETTE)])
    return r, g, b


def ascii_text(text: str) -> str:
    """``text`` as OpenCV can draw it: its fonts have ASCII only, and a name that is not UTF-8
    (a surrogate escape, as from a file ``v\\xff.mp4``) would crash ``cv2.putText``; others become ``?``."""
    return str(text).encode("ascii", "replace").decode("ascii")


def _scale(image: np.ndarray) -> float:
    return max(image.shape[0], image.shape[1]) / 1000.0


def draw_skeleton(image: np.ndarray, keypoints: np.ndarray, confidences: np.ndarray, color: Color,
                  min_confidence: float = MIN_DRAW_CONFIDENCE) -> None:
    """Draw one skeleton in place. keypoints: (17, 2) pixels; confidences: (17,)."""
    thick = max(1, round(2 * _scale(image)))
    seen = confidences > min_confidence
    pts = np.round(keypoints).astype(int)
    for a, b in COCO_BONES:
        if seen[a] and seen[b]:
            cv2.line(image, tuple(pts[a]), tuple(pts[b]), color, thick, cv2.LINE_AA)
    for p in pts[seen]:
        cv2.circle(image, tuple(p), thick + 2, color, -1, cv2.LINE_AA)


def draw_label(image: np.ndarray, text: str, anchor: Sequence[float] | np.ndarray, color: Color) -> None:
    """Draw ``text`` in place on a filled box whose bottom-left corner is ``anchor`` (u, v) pixels."""
    text = ascii_text(text)
    scale = 0.5 * _scale(image) + 0.2
    thick = max(1, round(_scale(image)))
    (w, h), base = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, thick)
    u = int(np.clip(anchor[0], 0, max(image.shape[1] - w - 2, 0)))
    v = int(np.clip(anchor[1], h + base + 2, image.shape[0]))
    cv2.rectangle(image, (u, v - h - base - 2), (u + w + 2, v), color, -1)
    text_color = (0, 0, 0) if sum(color) > 380 else (255, 255, 255)
    cv2.putText(image, text, (u + 1, v - base - 1), cv2.FONT_HERSHEY_SIMPLEX, scale, text_color, thick, cv2.LINE_AA)


def draw_persons(image: np.ndarray, keypoints: np.ndarray, confidences: np.ndarray, boxes: np.ndarray,
                 labels: list[str], keys: Iterable[int] | np.ndarray | None = None) -> np.ndarray:
    """A copy of ``image`` with skeletons, boxes and one label per person.

    keypoints: (N, 17, 2) pixels; confidences: (N, 17); boxes: (N, 4) pixels
    ``[u_min, v_min, u_max, v_max]``; labels: N strings; keys: (N,) ints choosing colours
    (track ids), by default the row numbers.
    """
    out = np.ascontiguousarray(image).copy()
    keys = range(len(keypoints)) if keys is None else keys
    thick = max(1, round(_scale(out)))
    for kp, conf, box, label, key in zip(keypoints, confidences, boxes, labels, keys):
        color = color_for(key)
        b = np.round(box).astype(int)
        cv2.rectangle(out, (b[0], b[1]), (b[2], b[3]), color, thick)
        draw_skeleton(out, kp, conf, color)
        draw_label(out, label, (b[0], b[1]), color)
    return out


def draw_detections(image: np.ndarray, detections: Detections) -> np.ndarray:
    """A copy of ``image`` with every detected skeleton and its score."""
    labels = [f"{s:.2f}" for s in detections.scores]
    return draw_persons(image, detections.keypoints, detections.confidences, detections.boxes, labels)


def draw_environment(image: np.ndarray, state: EnvironmentState, frame: Frame | None = None) -> np.ndarray:
    """A copy of ``image`` with the tracked pedestrians of an ``EnvironmentState``:
    skeleton, box, track id and distance from the camera in metres; with behaviour cues
    (``Config.behaviour``) also motion state, facing and conflict in the label, and, given the
    ``frame`` (its camera), the heading arrows and predicted paths
    (:mod:`pedenv.visualize.behaviour_drawing`)."""
    from pedenv.visualize.behaviour_drawing import behaviour_label, draw_behaviour_image

    peds = state.pedestrians
    labels = [f"id {int(i)}" + (f"  {d:.1f} m" if np.isfinite(d) else "") + behaviour_label(state, k)
              for k, (i, d) in enumerate(zip(peds.track_ids, peds.distances))]
    out = draw_persons(image, peds.keypoints, peds.confidences, peds.boxes, labels, keys=peds.track_ids)
    if frame is not None:
        draw_behaviour_image(out, state, frame.camera.intrinsics, frame.cam_to_world)
    return out
