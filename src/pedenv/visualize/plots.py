"""Pictures as the paper shows them: the environment model (Fig. 1) and error by distance (Fig. 3).

Figures are drawn with matplotlib's object API on the Agg canvas (no pyplot), so
importing pedenv leaves the user's matplotlib backend and open figures alone.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from pedenv.records import Frame
from pedenv.skeleton import COCO_BONES
from pedenv.state import EnvironmentState


def _figure(figsize: tuple[float, float]) -> Figure:
    """A figure on its own Agg canvas (inches), outside pyplot's figure manager."""
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _to_vehicle(points: np.ndarray, state: EnvironmentState) -> np.ndarray:
    """World points (..., 3) into the ego vehicle frame (x forward, y left, z up)."""
    return (points - state.ego.translation) @ state.ego.rotation


def plot_birds_eye(state: EnvironmentState, path: str | Path, frame: Frame | None = None, title: str = "") -> Path:
    """The environment model at one frame, in the ego vehicle's frame.

    Left: 3D view with the ego camera, pedestrians as red dots on the ground and their
    3D skeletons in blue. Right: top view with track ids, velocity arrows and, when
    ``frame`` has ground truth, the true positions as black crosses.
    """
    peds = state.pedestrians
    pos = _to_vehicle(peds.positions, state) if len(peds) else np.zeros((0, 3))
    fig = _figure((14, 6.5))
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    reach = max(20.0, float(np.max(pos[:, 0])) + 5 if len(pos) else 20.0)
    hfov = frame.camera.hfov if frame is not None else np.radians(64.5)
    for ax in (ax2,):
        for s in (-1, 1):
            ax.plot([0, reach * np.cos(hfov / 2)], [0, s * reach * np.sin(hfov / 2)], color="0.7", lw=0.8)
    ax2.scatter([0], [0], marker=(3, 0, -90), s=300, color="tab:green", label="ego camera")
    ax3.scatter([0], [0], [1.5], marker="^", s=120, color="tab:green")
    if len(peds):
        skel = _to_vehicle(peds.keypoints_3d, state)
        for i in range(len(peds)):
            seen = peds.confidences[i] > 0
            for a, b in COCO_BONES:
                if seen[a] and seen[b]:
                    ax3.plot(*skel[i, [a, b]].T, color="tab:blue", lw=1.0)
        ax3.scatter(pos[:, 0], pos[:, 1], pos[:, 2], color="tab:red", s=12)
        vel = peds.velocities[:, :2] @ state.ego.rotation[:2, :2]
        ax2.scatter(pos[:, 0], pos[:, 1], color="tab:red", s=18, label="pedestrians (pedenv)", zorder=3)
        ax2.quiver(pos[:, 0], pos[:, 1], vel[:, 0], vel[:, 1], color="tab:red", angles="xy", scale_units="xy",
                   scale=0.5, width=0.003)
        for i, tid in enumerate(peds.track_ids):
            ax2.annotate(str(tid), (pos[i, 0], pos[i, 1]), textcoords="offset points", xytext=(4, 4), fontsize=7)
    if frame is not None and frame.ground_truth is not None and len(frame.ground_truth):
        gt = (frame.ground_truth.positions - state.ego.translation) @ state.ego.rotation
        ax2.scatter(gt[:, 0], gt[:, 1], marker="x", color="black", s=22, label="ground truth", zorder=2)
    ax3.set_xlabel("x forward [m]")
    ax3.set_ylabel("y left [m]")
    ax3.set_zlabel("z [m]")
    ax3.view_init(elev=22, azim=-150)
    spans = [np.ptp(np.r_[0.0, pos[:, k]]) + 2.0 for k in (0, 1)] if len(pos) else [20.0, 20.0]
    ax3.set_box_aspect((spans[0], spans[1], 2.5 * 4))  # heights drawn 4x to show the skeletons
    ax2.set_xlim(-2, reach)
    ax2.set_ylim(-reach * 0.55, reach * 0.55)
    ax2.set_aspect("equal")
    ax2.set_xlabel("x forward [m]")
    ax2.set_ylabel("y left [m]")
    ax2.legend(loc="upper left", fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle(title or f"{state.scene} frame {state.frame_index}: {len(peds)} pedestrians")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path


def plot_error_by_distance(series: dict[str, list[dict]], path: str | Path, title: str = "") -> Path:
    """Mean absolute error per 1 m distance bin for each method (the paper's Fig. 3).

    series: label -> rows ``{"distance_m", "abs_error_m", "count"}`` as in ``Metrics.error_by_distance``.
    """
    fig = _figure((9, 6))
    ax, axn = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [3, 1]})
    for label, rows in series.items():
        if not rows:
            continue
        d = np.array([r["distance_m"] for r in rows]) + 0.5
        ax.plot(d, [r["abs_error_m"] for r in rows], lw=1.2, label=label)
        axn.plot(d, [r["count"] for r in rows], lw=1.0, label=label)
    ax.set_ylabel("absolute error [m]")
    axn.set_ylabel("# pedestrians")
    axn.set_xlabel("distance ego - pedestrian [m]")
    ax.grid(alpha=0.3)
    axn.grid(alpha=0.3)
    ax.legend()
    ax.set_title(title or "Absolute error over distance")
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path
