"""The behaviour cues in the Rerun recording (:mod:`pedenv.outputs.rerun_log` calls :func:`log_behaviour`).

Entities under ``world/behaviour``: ``headings`` (arrows on the ground, orange), ``paths``
(the predicted path of each pedestrian, purple; red in conflict with the ego's path),
``ellipses`` (1-sigma outlines at each horizon) and ``ego_path`` (the ego's predicted path).
"""

from __future__ import annotations

import numpy as np
import rerun as rr

from pedenv.state import EnvironmentState
from pedenv.visualize.behaviour_shapes import CONFLICT_RGB, HEADING_RGB, PATH_RGB, behaviour_shapes


def log_behaviour(rec: rr.RecordingStream, state: EnvironmentState) -> None:
    """Log (or clear, with behaviour off) the behaviour entities of one frame."""
    shapes = behaviour_shapes(state.pedestrians)
    if shapes is None:
        return
    z = state.pedestrians.positions[:, 2]
    lift = lambda xy, height: np.concatenate([xy, np.broadcast_to(height, xy.shape[:-1] + (1,))], axis=-1)  # noqa: E731
    origins = lift(shapes.arrow_origins, z[shapes.arrow_rows, None] + 0.05)
    rec.log("world/behaviour/headings", rr.Arrows3D(origins=origins, vectors=lift(shapes.arrow_vectors, 0.0),
                                                    colors=[HEADING_RGB]))
    colours = [CONFLICT_RGB if c else PATH_RGB for c in shapes.conflict]
    rec.log("world/behaviour/paths", rr.LineStrips3D([lift(p, zz) for p, zz in zip(shapes.paths, z)], colors=colours))
    rings = [lift(r, zz) for rs, zz in zip(shapes.ellipses, z) for r in rs]
    ring_colours = [c for c in colours for _ in range(shapes.ellipses.shape[1])]
    rec.log("world/behaviour/ellipses", rr.LineStrips3D(rings, colors=ring_colours))
    ground = float(state.ego.translation[2])
    rec.log("world/behaviour/ego_path", rr.LineStrips3D([lift(shapes.ego_path, ground)], colors=[PATH_RGB]))
