"""The behaviour cues in the MCAP file (:mod:`pedenv.outputs.mcap_log` adds these primitives to
each pedestrian's entity): a heading arrow (orange), the predicted path (purple; red in conflict
with the ego's path) with a 1-sigma ellipse at each horizon, and the ego's predicted path."""

from __future__ import annotations

from foxglove import messages as fm

from pedenv.state import EnvironmentState
from pedenv.visualize.behaviour_shapes import CONFLICT_RGB, HEADING_RGB, PATH_RGB, BehaviourShapes


def _colour(rgb: tuple[int, int, int]) -> fm.Color:
    return fm.Color(r=rgb[0] / 255, g=rgb[1] / 255, b=rgb[2] / 255, a=1.0)


def _pose(x: float, y: float, z: float, yaw: float) -> fm.Pose:
    import numpy as np

    return fm.Pose(position=fm.Vector3(x=x, y=y, z=z),
                   orientation=fm.Quaternion(z=float(np.sin(yaw / 2)), w=float(np.cos(yaw / 2))))


def pedestrian_primitives(state: EnvironmentState, shapes: BehaviourShapes | None, i: int
                          ) -> tuple[list[fm.ArrowPrimitive], list[fm.LinePrimitive]]:
    """Arrows and lines of pedestrian ``i`` (none with behaviour off)."""
    if shapes is None:
        return [], []
    b = state.pedestrians.behaviour
    assert b is not None  # shapes exist only with behaviour
    z = float(state.pedestrians.positions[i, 2]) + 0.05
    arrows = []
    if b.orientation_availability[i] > 0:
        x, y = state.pedestrians.positions[i, :2]
        arrows.append(fm.ArrowPrimitive(pose=_pose(float(x), float(y), z, float(b.yaw[i])), shaft_length=0.9,
                                        shaft_diameter=0.08, head_length=0.3, head_diameter=0.22,
                                        color=_colour(HEADING_RGB)))
    colour = _colour(CONFLICT_RGB if shapes.conflict[i] else PATH_RGB)
    point = lambda xy: fm.Point3(x=float(xy[0]), y=float(xy[1]), z=z)  # noqa: E731
    lines = [fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineStrip, thickness=0.06, color=colour,
                              points=[point(p) for p in shapes.paths[i]])]
    lines += [fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineLoop, thickness=0.02, color=colour,
                               points=[point(p) for p in ring[:-1]]) for ring in shapes.ellipses[i]]
    return arrows, lines


def ego_path_line(shapes: BehaviourShapes | None, ground_z: float) -> list[fm.LinePrimitive]:
    """The ego's predicted path as a line (none with behaviour off)."""
    if shapes is None:
        return []
    return [fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineStrip, thickness=0.1, color=_colour(PATH_RGB),
                             points=[fm.Point3(x=float(x), y=float(y), z=ground_z) for x, y in shapes.ego_path])]
