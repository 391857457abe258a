"""The behaviour cues drawn with OpenCV: on the camera image (:func:`draw_behaviour_image`, called
by :func:`pedenv.visualize.overlay.draw_environment`) and in the bird's-eye video
(:func:`draw_behaviour_birds_eye`, called by :class:`pedenv.visualize.birds_eye_video.BirdsEyeVideo`).

Heading arrows orange, predicted paths purple with their 1-sigma ellipses, both red for a
pedestrian in conflict with the ego's path; the ego's predicted path purple.
"""

from __future__ import annotations

from collections.abc import Callable

import cv2
import numpy as np

from pedenv.geometry import invert_transform, project
from pedenv.state import EnvironmentState
from pedenv.visualize.behaviour_shapes import CONFLICT_RGB, HEADING_RGB, PATH_RGB, behaviour_shapes


def behaviour_label(state: EnvironmentState, i: int) -> str:
    """A short text of pedestrian ``i``'s cues ("" with behaviour off): motion state, facing, conflict."""
    b = state.pedestrians.behaviour
    if b is None:
        return ""
    from pedenv.state import MOTION_STATES

    text = f"  {MOTION_STATES[int(b.motion_state[i])]}"
    if b.facing_probability[i] >= 0.5:
        text += "  facing"
    if b.conflict_probability[i] >= 0.5:
        text += f"  CONFLICT {b.conflict_time[i]:.1f} s"
    return text


def draw_behaviour_image(image: np.ndarray, state: EnvironmentState, intrinsics: np.ndarray,
                         cam_to_world: np.ndarray) -> None:
    """Draw in place (RGB image) the heading arrows and predicted paths projected into the camera:
    intrinsics (3, 3), cam_to_world (4, 4) of the frame."""
    shapes = behaviour_shapes(state.pedestrians, segments=16)
    if shapes is None or not len(state.pedestrians):
        return
    world_to_cam = invert_transform(cam_to_world)
    z = state.pedestrians.positions[:, 2]

    def pixels(xy: np.ndarray, height: float) -> np.ndarray | None:
        pts = np.column_stack([xy, np.full(len(xy), height)])
        uv, depth = project(pts, intrinsics, world_to_cam)
        return None if (depth < 0.5).any() else np.round(uv).astype(np.int32)

    for i in range(len(state.pedestrians)):
        colour = CONFLICT_RGB if shapes.conflict[i] else PATH_RGB
        path = pixels(shapes.paths[i], float(z[i]))
        if path is not None:
            cv2.polylines(image, [path], False, colour, 2, cv2.LINE_AA)
        for ring in shapes.ellipses[i]:
            uv = pixels(ring, float(z[i]))
            if uv is not None:
                cv2.polylines(image, [uv], True, colour, 1, cv2.LINE_AA)
    for row, origin, vector in zip(shapes.arrow_rows, shapes.arrow_origins, shapes.arrow_vectors):
        uv = pixels(np.array([origin, origin + vector]), float(z[row]) + 0.05)
        if uv is not None:
            cv2.arrowedLine(image, tuple(int(v) for v in uv[0]), tuple(int(v) for v in uv[1]), HEADING_RGB, 2,
                            cv2.LINE_AA, tipLength=0.3)


def draw_behaviour_birds_eye(img: np.ndarray, state: EnvironmentState, to_vehicle: Callable,
                             px: Callable) -> None:
    """Draw in place (BGR picture) the cues seen from above: ``to_vehicle`` maps world points (..., 3)
    to vehicle x-y (..., 2), ``px`` vehicle x-y to picture pixels."""
    shapes = behaviour_shapes(state.pedestrians, segments=16)
    if shapes is None:
        return
    bgr = lambda rgb: rgb[::-1]  # noqa: E731
    lift = lambda xy: np.concatenate([xy, np.zeros(xy.shape[:-1] + (1,))], axis=-1) + [0, 0, state.ego.translation[2]]  # noqa: E731
    if len(shapes.ego_path) > 1:
        cv2.polylines(img, [px(to_vehicle(lift(shapes.ego_path)))], False, bgr(PATH_RGB), 2, cv2.LINE_AA)
    for i in range(len(state.pedestrians)):
        colour = bgr(CONFLICT_RGB if shapes.conflict[i] else PATH_RGB)
        cv2.polylines(img, [px(to_vehicle(lift(shapes.paths[i])))], False, colour, 1, cv2.LINE_AA)
        for ring in shapes.ellipses[i]:
            cv2.polylines(img, [px(to_vehicle(lift(ring)))], True, colour, 1, cv2.LINE_AA)
    for origin, vector in zip(shapes.arrow_origins, shapes.arrow_vectors):
        a, b = px(to_vehicle(lift(np.array([origin, origin + vector]))))
        cv2.arrowedLine(img, (int(a[0]), int(a[1])), (int(b[0]), int(b[1])), bgr(HEADING_RGB), 2, cv2.LINE_AA,
                        tipLength=0.35)
