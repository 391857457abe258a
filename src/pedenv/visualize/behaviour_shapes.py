"""What the viewers draw of the behaviour cues (:class:`pedenv.state.Behaviour`): heading arrows,
predicted paths with their ellipses, and which pedestrians are in conflict with the ego's path."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pedenv.state import Behaviour, Pedestrians
from pedenv.visualize.shapes import covariance_ellipses

#: Length (metres) of a heading arrow on the ground.
HEADING_ARROW_M = 1.2
#: Colours (RGB 0-255): heading, predicted path, conflict.
HEADING_RGB, PATH_RGB, CONFLICT_RGB = (250, 170, 20), (120, 60, 200), (230, 20, 20)
#: A pedestrian is drawn in conflict when its probability reaches this (the estimator's own threshold
#: is :data:`pedenv.behaviour.conflict.CONFLICT_PROBABILITY`; the state carries only the probability).
CONFLICT_DRAW_PROBABILITY = 0.5


@dataclass(frozen=True)
class BehaviourShapes:
    """World x-y shapes (metres) of N pedestrians: heading arrows ``arrow_origins`` (M, 2) and
    ``arrow_vectors`` (M, 2) for the M with an orientation (available or sign unknown); ``paths``
    (N, H + 1, 2) from the position through the predicted positions; ``ellipses`` (N, H, S, 2),
    the 1-sigma outline at each horizon (2 sigma at 3 s covers most of a street); ``conflict``
    (N,) bool; ``ego_path`` (K, 2)."""

    arrow_origins: np.ndarray
    arrow_vectors: np.ndarray
    arrow_rows: np.ndarray
    paths: np.ndarray
    ellipses: np.ndarray
    conflict: np.ndarray
    ego_path: np.ndarray


def behaviour_shapes(peds: Pedestrians, segments: int = 24) -> BehaviourShapes | None:
    """The shapes of ``peds``' behaviour, or None where it has none (behaviour off)."""
    b: Behaviour | None = peds.behaviour
    if b is None:
        return None
    n, h = len(b), len(b.horizons)
    rows = np.flatnonzero(b.orientation_availability > 0)
    vectors = HEADING_ARROW_M * np.column_stack([np.cos(b.yaw[rows]), np.sin(b.yaw[rows])])
    paths = np.concatenate([peds.positions[:, None, :2], b.predicted_positions], axis=1)
    rings = covariance_ellipses(b.predicted_positions.reshape(-1, 2), b.predicted_covariances.reshape(-1, 2, 2),
                                sigma=1.0, segments=segments).reshape(n, h, segments + 1, 2)
    return BehaviourShapes(peds.positions[rows, :2], vectors, rows, paths, rings,
                           b.conflict_probability >= CONFLICT_DRAW_PROBABILITY, b.ego_path)
