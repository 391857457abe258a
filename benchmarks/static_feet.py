"""Where a static camera's ground cue puts MOT17's whole persons, in pixels: the network's ankle
keypoints against the truth box's bottom, frame by frame.

    PYTHONPATH=src python benchmarks/static_feet.py [--samples ../shared/samples/real] [--rows]
        [--only MOT17-02-FRCNN,...] [--set FIELD=VALUE]

For each one-to-one match (box IoU >= 0.5) of the fused static run (the defaults, ``--detection
far`` as ``static_cameras.py`` runs it) and each of the network's ankles seen (confidence >= the
fused cues' ``min_keypoint_confidence``), with the truth box's bottom centre ``b`` and its ground
point ``T`` at range ``r`` (the scene's truth):

* ``dv``: px, ``b``'s row minus the ankle's row (how far above the box bottom the ankle is seen);
* ``dv_model``: px, the same for a point ``ankle_height`` (the ground cue's lift) straight above
  ``T``: what the ground cue assumes;
* ``a``: metres, the height of the ankle's ray where it passes over ``T``'s range: the ankle
  height this truth implies (the ground cue lifts the plane by ``ankle_height``);
* ``e``: metres, the range of the ankle ray's cut with the lifted plane minus ``r`` (the ground
  cue of that ankle alone against this truth); ``e_box``: the same for the network's own box's
  bottom centre cut with the ground (no lift);
* ``du``: px, the ankle's column minus ``b``'s (a foot ahead or aside);
* ``bottoms``: px, the truth box's bottom row minus the network's box's;
* ``a_net``: metres, like ``a`` over the ground point of the network's own box bottom;
* ``foot``: px, how far half a foot's length ahead toward the camera moves ``T`` down the image;
* ``e_pitch``, ``e_height``: ``e`` with the camera pitched 0.5 deg further down, or 0.1 m
  higher, truth and cue cut with that camera alike (an error of the estimated calibration).

Printed per scene and per truth person (means over its frames), the lower ankle (the one the cue
prefers) and the other; ``--rows`` also prints each frame. Then the run's whole-person estimates'
errors along and across the ray, with the reported sigma along it, split by whether the ground
cue was used. ``--set`` changes a ``fused`` setting (``cues=ground``: the ground cue alone). The
keypoints stay in memory: the samples' licences forbid shipping anything derived image by image.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
from static_cameras import DEFAULT_SAMPLES, STATIC_MOT17

ANKLES = (15, 16)
#: The columns of :attr:`Rows.rows` (module notes): ``foot`` px that half a foot's length
#: (:data:`FOOT_AHEAD_M`) ahead toward the camera moves a ground point down the image, ``bottoms`` px
#: the truth box's bottom below the network's, ``e_pitch`` / ``e_height`` ``e`` with the camera
#: pitched :data:`PITCH_DEG` further down / :data:`HEIGHT_M` higher (truth and cue alike).
COLUMNS = ("frame", "id", "lower", "dv", "du", "dv_model", "e_box", "r", "box_px", "bottoms", "foot", "a", "a_net",
           "e", "e_pitch", "e_height")
C = {name: k for k, name in enumerate(COLUMNS)}
#: Half of a foot's length (Winter: 0.152 of the 1.72 m body height), metres.
FOOT_AHEAD_M = 0.5 * 0.152 * 1.72
#: The calibration's perturbations of the sensitivity columns: pitch (deg) and height (m).
PITCH_DEG = 0.5
HEIGHT_M = 0.1
#: Persons listed with the largest errors along the ray.
WORST = 5


def lifted_range(camera, pixel: np.ndarray, lift: float) -> float:
    """Horizontal range, metres, where the ray of ``pixel`` (2,) px meets the plane ``lift``
    metres above the ground (vehicle frame of ``camera``); inf above its horizon."""
    ray = camera.cam_to_vehicle[:3, :3] @ np.linalg.inv(camera.intrinsics) @ np.array([pixel[0], pixel[1], 1.0])
    origin = camera.cam_to_vehicle[:3, 3]
    if ray[2] >= -1e-9:
        return float("inf")
    s = (lift - origin[2]) / ray[2]
    return float(np.hypot(*(origin[:2] + s * ray[:2] - origin[:2])))


def height_at_range(camera, pixel: np.ndarray, r: float) -> float:
    """Metres above the ground of the ray of ``pixel`` (2,) px where its horizontal range is ``r``."""
    ray = camera.cam_to_vehicle[:3, :3] @ np.linalg.inv(camera.intrinsics) @ np.array([pixel[0], pixel[1], 1.0])
    return float(camera.cam_to_vehicle[2, 3] + ray[2] * r / np.hypot(ray[0], ray[1]))


def project(camera, point: np.ndarray) -> np.ndarray:
    """(2,) px of the vehicle-frame ``point`` (3,) metres."""
    cam = np.linalg.inv(camera.cam_to_vehicle)
    x = camera.intrinsics @ (cam[:3, :3] @ point + cam[:3, 3])
    return x[:2] / x[2]


def along_across(camera, estimate: np.ndarray, truth: np.ndarray, cov: np.ndarray) -> tuple[float, float, float]:
    """The error of ``estimate`` (2,) against ``truth`` (2,) (ground x-y, metres) along and across
    the camera's ray to the truth, and the reported sigma along it from ``cov`` (2, 2) m^2."""
    ray = truth - camera.cam_to_vehicle[:2, 3]
    ray /= np.linalg.norm(ray)
    d = estimate - truth
    return float(d @ ray), float(d @ np.array([-ray[1], ray[0]])), float(np.sqrt(ray @ cov @ ray))


def perturbed(camera, pitch_deg: float = 0.0, lift_m: float = 0.0):
    """``camera`` pitched ``pitch_deg`` further down (about its own x axis) and ``lift_m`` higher."""
    from pedenv.records import Camera

    c, s = np.cos(np.radians(pitch_deg)), np.sin(np.radians(pitch_deg))
    t = camera.cam_to_vehicle.copy()
    t[:3, :3] = t[:3, :3] @ np.array([[1.0, 0, 0], [0, c, s], [0, -s, c]])
    t[2, 3] += lift_m
    return Camera(camera.intrinsics, camera.width, camera.height, t, camera.mount)


def ankle_row(cams: tuple, uv: np.ndarray, b: np.ndarray, r: float, r_box: float, lift: float) -> tuple:
    """(a, a_net, e, e with the camera pitched ``PITCH_DEG``, e with it ``HEIGHT_M`` higher) of the
    ankle at ``uv`` (2,) px: ``cams`` the scene's camera and the two perturbed ones, ``b`` (2,) px the
    truth box's bottom centre at range ``r``, ``r_box`` the network's box bottom's range (metres);
    a perturbed camera's truth is its own cut of ``b`` (as the truth would be made with it)."""
    cam = cams[0]
    e_perturbed = [lifted_range(c, uv, lift) - lifted_range(c, b, 0.0) for c in cams[1:]]
    return (height_at_range(cam, uv, r), height_at_range(cam, uv, r_box), lifted_range(cam, uv, lift) - r,
            *e_perturbed)


def foot_pixels(camera, ground: np.ndarray, ahead: float) -> float:
    """px the image of the ground point ``ground`` (3,) metres moves down when it moves ``ahead``
    metres toward the camera along the ground."""
    ray = ground[:2] - camera.cam_to_vehicle[:2, 3]
    step = np.append(-ahead * ray / np.linalg.norm(ray), 0.0)
    return float(project(camera, ground + step)[1] - project(camera, ground)[1])


@dataclasses.dataclass
class Rows:
    """Per ankle seen on a whole person found (``rows``, :data:`COLUMNS`). Per whole person
    found (``estimates``): (frame, truth id, r, along, across, sigma along, 1 where the ground cue was
    used) of the run's estimate."""

    lift: float
    min_conf: float
    rows: list = dataclasses.field(default_factory=list)
    estimates: list = dataclasses.field(default_factory=list)
    frame_no: int = 0

    def on_frame(self, state, frame) -> None:
        from pedenv.evaluation.matching import match_one_to_one

        self.frame_no += 1
        peds, truth, cam = state.pedestrians, frame.ground_truth, frame.camera
        if truth is None:
            return
        cams = (cam, perturbed(cam, pitch_deg=PITCH_DEG), perturbed(cam, lift_m=HEIGHT_M))
        pick = match_one_to_one(peds.boxes, truth.boxes)
        for i in np.flatnonzero(pick >= 0):
            t, nb = pick[i], peds.boxes[i]
            box = truth.boxes[t]
            b = np.array([0.5 * (box[0] + box[2]), box[3]])
            tp = np.append(truth.positions[t, :2], 0.0)
            r = float(np.hypot(*(tp[:2] - cam.cam_to_vehicle[:2, 3])))
            used = "ground" in str(peds.sources[i]).split(";")[0].split("+")
            self.estimates.append((self.frame_no, int(truth.ids[t]), r,
                                   *along_across(cam, peds.positions[i, :2], tp[:2], peds.covariances[i]), used))
            r_box = lifted_range(cam, np.array([0.5 * (nb[0] + nb[2]), nb[3]]), 0.0)
            common = (b[1] - project(cam, tp + np.array([0, 0, self.lift]))[1], r_box - r, r, box[3] - box[1],
                      box[3] - nb[3], foot_pixels(cam, tp, FOOT_AHEAD_M))
            seen = [k for k in ANKLES if peds.confidences[i, k] >= self.min_conf]
            low = max(seen, key=lambda k: peds.keypoints[i, k, 1]) if seen else None
            for k in seen:
                uv = peds.keypoints[i, k]
                self.rows.append((self.frame_no, int(truth.ids[t]), k == low, b[1] - uv[1], uv[0] - b[0], *common,
                                  *ankle_row(cams, uv, b, r, r_box, self.lift)))


def run_scene(name: str, samples: Path, fused: dict) -> Rows:
    """The rows (:class:`Rows`) of one MOT17 static scene run with ``fused`` settings over the defaults."""
    from pedenv.apps.scene_result import SceneHooks, evaluate_scene
    from pedenv.config import Config
    from pedenv.datasets.ucmctrack import mot17_static_scene
    from pedenv.detection import backend_options, create_detector
    from pedenv.localization import configure
    from pedenv.localization.fused.ground import ankle_height

    root = samples / "mot17"
    scene = mot17_static_scene(root / name, root / "ucmctrack_cam_para" / f"{name}.txt")
    config = configure(Config(), "fused")
    config = dataclasses.replace(config, fused=dataclasses.replace(config.fused, **fused))
    rows = Rows(ankle_height(config.fused), config.fused.min_keypoint_confidence)
    backend = create_detector("onnx", **backend_options("onnx", detection="far", score_threshold=0.1))
    evaluate_scene(scene.name, scene.frames, config=config, backend=backend, hooks=SceneHooks(on_frame=rows.on_frame))
    return rows


def summary(rows: np.ndarray) -> str:
    """The means of ``rows`` (:data:`COLUMNS`) as the table's cells, and ``e``'s RMS."""
    m = dict(zip(COLUMNS, rows.mean(axis=0)))
    return (f"{len(rows)} | {m['dv']:.1f} | {m['dv_model']:.1f} | {m['bottoms']:+.1f} | {m['foot']:.1f} | "
            f"{m['du']:+.1f} | {m['a']:.3f} | {m['a_net']:.3f} | {m['e']:+.3f} | {m['e_box']:+.3f} | "
            f"{np.sqrt((rows[:, C['e']] ** 2).mean()):.3f} | {m['e_pitch']:+.3f} | {m['e_height']:+.3f}")


def print_ankles(name: str, rows: np.ndarray, lift: float, every: bool) -> None:
    """Per person (by range) the lower ankle's means (:func:`summary`), then all, then the other ankle."""
    print(f"\n{name} (lift {lift:.3f} m): per person, the lower ankle's means; px: dv, dv_model, bottoms, foot, "
          f"du; m: a, a_net, e, e_box, e RMS, e with the camera {PITCH_DEG} deg down / {HEIGHT_M} m up")
    print("| id | range m | box px | n | dv | dv_model | bottoms | foot | du | a | a_net | e | e_box | e RMS | "
          "e_pitch | e_height |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    lower = rows[rows[:, C["lower"]] == 1]
    ids = lower[:, C["id"]].astype(int)
    for pid in sorted(set(ids), key=lambda p: lower[ids == p, C["r"]].mean()):
        p = lower[ids == pid]
        print(f"| {pid} | {p[:, C['r']].mean():.1f} | {p[:, C['box_px']].mean():.0f} | {summary(p)} |")
    print(f"| all, lower ankle | | | {summary(lower)} |")
    if (rows[:, C["lower"]] == 0).any():
        print(f"| all, other ankle | | | {summary(rows[rows[:, C['lower']] == 0])} |")
    if every:
        print("  " + " ".join(COLUMNS))
        for row in rows:
            print("  " + " ".join(f"{x:.3f}" for x in row))


def print_estimates(estimates: np.ndarray) -> None:
    """The run's whole-person errors along / across the ray: mean, RMS, the reported sigma along (RMS)."""
    if not len(estimates):
        return
    along, across, sigma = estimates[:, 3], estimates[:, 4], estimates[:, 5]
    print(f"estimates ({len(estimates)} whole-person matches): along the ray mean {along.mean():+.3f} m, "
          f"RMS {np.sqrt((along**2).mean()):.3f} m (reported sigma RMS {np.sqrt((sigma**2).mean()):.3f} m); "
          f"median |along| {np.median(np.abs(along)):.3f} m; across RMS {np.sqrt((across**2).mean()):.3f} m")
    g = estimates[:, 6] == 1
    print(f"  with the ground cue used ({g.sum()}): along mean {along[g].mean():+.3f} m, RMS "
          f"{np.sqrt((along[g] ** 2).mean()):.3f} m (reported {np.sqrt((sigma[g] ** 2).mean()):.3f} m); without it "
          f"({(~g).sum()}): RMS {np.sqrt((along[~g] ** 2).mean()) if (~g).any() else float('nan'):.3f} m")
    ids = estimates[:, 1].astype(int)
    worst = sorted(set(ids), key=lambda p: -np.abs(along[ids == p]).mean())[:WORST]
    print("  largest mean |along| (id: range m, along m per frame): " + "; ".join(
        f"{p}: {estimates[ids == p, 2].mean():.1f}, " + " ".join(f"{x:+.2f}" for x in along[ids == p])
        for p in worst))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--only", default=",".join(STATIC_MOT17))
    parser.add_argument("--rows", action="store_true", help="also print every frame's ankle")
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                        help="a fused setting (e.g. cues=ground, ankle_keypoint_offset_m=0.0); repeatable")
    args = parser.parse_args(argv)
    fused = {k: (v if k == "cues" else float(v)) for k, v in (item.split("=", 1) for item in args.set)}
    for name in args.only.split(","):
        rows = run_scene(name, args.samples, fused)
        print_ankles(name, np.array(rows.rows, float).reshape(-1, len(COLUMNS)), rows.lift, args.rows)
        print_estimates(np.array(rows.estimates, float).reshape(-1, 7))
    return 0


if __name__ == "__main__":
    sys.exit(main())
