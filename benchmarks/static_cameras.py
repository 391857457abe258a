"""Static cameras: the paper's method, fused with ``mount: vehicle`` and fused with ``mount: static``.

    PYTHONPATH=src python benchmarks/static_cameras.py [--samples ../shared/samples/real]
        [--only mot17|synthetic] [--json OUT.json] [--breakdown] [--persons] [--set FIELD=VALUE]

Real data: MOT17-02, -04 and -09 (static cameras) with UCMCTrack's estimated cameras
(:mod:`pedenv.datasets.ucmctrack`); the ground truth is each evaluated ground-truth box's bottom
centre cut with the ground plane. Detections: the real network, ``--detection far`` (the
onnx backend as ``pedenv run`` makes it, with re-detection in crops for the fused preset).
Synthetic: the ``static-plaza`` scene (seed 0, flat; a camera 6 m up, 20 deg down), exact
truth, with the detector model's ``yolo11n-pose-far`` profile and with exact skeletons.

Rows: the paper's method; fused with ``mount: vehicle``; fused with ``mount: static`` (the
defaults: an estimated camera's tilt and height errors and the real network's ankle keypoint
offset and its spread across persons, ``fused.static_camera_*`` and
``fused.ankle_keypoint_offset_m`` / ``_std_m``); and fused static
with an exactly known camera and anatomical ankles (:data:`EXACT`, right for the synthetic
scene, the settings before these terms existed). ``--set FIELD=VALUE`` changes a ``fused``
setting of every fused row (an ablation).

``--persons`` prints per MOT17 scene a table of the fused vehicle and static rows person by
person (:mod:`pedenv.evaluation.static_pairs`): each truth's whole-person matches and the protocol's pairs scored
against it, its own estimate's and the others'. Against MOT17's box-bottom truth the coverages
are also given with that truth's own uncertainty added to the reported covariance
(:mod:`pedenv.evaluation.box_truth`: the slant of upright people under a camera looking down, a foot's length).

Per case: mean relative error (% of the camera-to-truth distance, the paper's matching:
each estimate with the nearest truth whose box overlaps its box at all, so a fragment of a
person found on its own counts against the position), the same over the one-to-one matches
(box IoU >= 0.5: the position of whole persons found), the share of errors inside the 1-
and 2-sigma ellipses (ideal 39.3 / 86.5 %; one-to-one matches), and the share of estimates
whose ground cue declined ``beyond-range``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

from pedenv.evaluation.static_pairs import Pairs, breakdown, coverage_with_truth, persons, print_persons

DEFAULT_SAMPLES = Path(__file__).resolve().parents[2] / "shared" / "samples" / "real"
STATIC_MOT17 = ("MOT17-02-FRCNN", "MOT17-04-FRCNN", "MOT17-09-FRCNN")
#: ``fused`` settings of an exactly known camera seen by exact skeletons: no calibration error, the
#: ankle keypoint at the anatomical height (what the fused method did before these terms).
EXACT = {"static_camera_tilt_std_deg": 0.0, "static_camera_height_std_m": 0.0, "ankle_keypoint_offset_m": 0.0,
         "ankle_keypoint_offset_std_m": 0.0}
#: (label, position method, camera mount, ``fused`` settings over the defaults)
VARIANTS = (("paper", "paper", "static", {}), ("fused vehicle", "fused", "vehicle", {}),
            ("fused static", "fused", "static", {}), ("fused static, exact camera", "fused", "static", EXACT))


def remount(scene, mount: str):
    """``scene`` with every frame's camera mounted ``mount``."""
    from pedenv.records import Camera, Scene

    def cam(c):
        return Camera(c.intrinsics, c.width, c.height, c.cam_to_vehicle, mount)

    return Scene(scene.name, tuple(dataclasses.replace(f, camera=cam(f.camera)) for f in scene.frames),
                 scene.description)


def evaluate(scene, method: str, backend, fused: dict | None = None, box_truth: bool = False) -> dict:
    """One scene through a fresh model: the figures of the table. fused: settings of the
    ``fused`` section over the defaults. box_truth: the truth is box bottoms (MOT17): also the
    coverages with its own uncertainty added (:mod:`pedenv.evaluation.box_truth`)."""
    from pedenv.apps.scene_result import SceneHooks, evaluate_scene, merge_scene_results
    from pedenv.config import Config
    from pedenv.localization import configure

    config = configure(Config(), method)
    if fused:
        config = dataclasses.replace(config, fused=dataclasses.replace(config.fused, **fused))
    pairs = Pairs(box_truth)
    start = time.perf_counter()
    result = evaluate_scene(scene.name, scene.frames, config=config, backend=backend,
                            hooks=SceneHooks(on_frame=pairs.on_frame))
    metrics = merge_scene_results([result], {"scenes": [scene.name]}).metrics
    o, c = metrics.overall, metrics.calibration
    declined = sum("ground:beyond-range" in s for s in pairs.sources)
    one, protocol = pairs.arrays()
    return {"rel_error_pct": round(o.rel_error_pct, 2), "abs_error_m": round(o.abs_error_m, 3), "count": o.count,
            "rel_error_one_to_one_pct": round(float(one[:, 0].mean()), 2) if len(one) else float("nan"),
            "count_one_to_one": len(one),
            "within_1sigma": round(100 * c.get("within_1sigma", float("nan")), 1),
            "within_2sigma": round(100 * c.get("within_2sigma", float("nan")), 1),
            "ground_beyond_range_pct": round(100 * declined / max(len(pairs.sources), 1), 1),
            **coverage_with_truth(pairs.with_truth),
            "breakdown": breakdown(protocol[:, :3]), "persons": persons(one, protocol, len(protocol)),
            "seconds": round(time.perf_counter() - start, 1)}


def cases(samples: Path, only: str | None):
    """(scene label, scene, backend label, backend factory)."""
    from pedenv.detection import backend_options, create_detector

    def onnx_far():
        return create_detector("onnx", **backend_options("onnx", detection="far", score_threshold=0.1))

    if only in (None, "mot17"):
        from pedenv.datasets.ucmctrack import mot17_static_scene

        root = samples / "mot17"
        for name in STATIC_MOT17:
            scene = mot17_static_scene(root / name, root / "ucmctrack_cam_para" / f"{name}.txt")
            yield name, scene, "onnx far", onnx_far
    if only in (None, "synthetic"):
        from pedenv.synthetic import generate_scenes

        scene = generate_scenes(0, ["static-plaza"])[0]
        yield "static-plaza", scene, "detector model (yolo11n-pose-far)", (
            lambda: create_detector("detector-model:yolo11n-pose-far"))
        yield "static-plaza", scene, "exact skeletons", lambda: create_detector("ground-truth")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=Path, default=DEFAULT_SAMPLES)
    parser.add_argument("--only", choices=("mot17", "synthetic"))
    parser.add_argument("--json", type=Path, help="Also write the figures here.")
    parser.add_argument("--breakdown", action="store_true",
                        help="also print where each fused row's mean comes from (whole persons, others, range)")
    parser.add_argument("--persons", action="store_true",
                        help="also print per MOT17 scene a per-person table of the fused vehicle and static rows")
    parser.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                        help="a fused setting for every fused row (e.g. static_camera_tilt_std_deg=0.5); repeatable")
    args = parser.parse_args(argv)
    overrides = {k: float(v) for k, v in (item.split("=", 1) for item in args.set)}
    rows = []
    print("| scene | detections | method | mean rel. error | abs. error | matched | rel. error one-to-one (n) | "
          "1 sigma | 2 sigma | 1 / 2 sigma, truth's uncertainty added | ground beyond range |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for label, scene, detections, make_backend in cases(args.samples, args.only):
        backend = make_backend()  # one per scene: the network's state stays within it
        results = {}
        for name, method, mount, fused in VARIANTS:
            f = results[name] = evaluate(remount(scene, mount), method, backend, {**overrides, **fused},
                                         box_truth=label in STATIC_MOT17)
            rows.append({"scene": label, "detections": detections, "method": name, **f})
            print_row(label, detections, name, f, args.breakdown and method == "fused")
        if args.persons and label in STATIC_MOT17:
            print_persons(label, results)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2) + "\n")
    return 0


def truth_coverage(f: dict) -> str:
    """The coverages with the truth's own uncertainty added, as a table cell ('-': exact truth)."""
    if "within_1sigma_with_truth" not in f:
        return "-"
    return f"{f['within_1sigma_with_truth']:.1f} / {f['within_2sigma_with_truth']:.1f} %"


def print_row(label: str, detections: str, name: str, f: dict, breakdown: bool) -> None:
    """One row of the main table (figures of :func:`evaluate`), with its breakdown line if asked."""
    print(f"| {label} | {detections} | {name} | {f['rel_error_pct']:.2f} % | {f['abs_error_m']:.3f} m | "
          f"{f['count']} | {f['rel_error_one_to_one_pct']:.2f} % ({f['count_one_to_one']}) | "
          f"{f['within_1sigma']:.1f} % | {f['within_2sigma']:.1f} % | {truth_coverage(f)} | "
          f"{f['ground_beyond_range_pct']:.1f} % |", flush=True)
    if breakdown:
        print("|  | breakdown: [count, mean %, points of the mean] | " + "; ".join(
            f"{k} {v}" for k, v in f["breakdown"].items()) + " ||||||||", flush=True)


if __name__ == "__main__":
    sys.exit(main())
