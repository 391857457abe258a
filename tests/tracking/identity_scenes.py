"""Identity figures of the tracker on the synthetic scenes: before and after the changes
beyond the paper (two-stage association, projected Kalman gate, memory of lost tracks).

Run it to print the table (seeded, detector-model backend, rolling terrain):

    PYTHONPATH=src python tests/tracking/identity_scenes.py [duration_s]
"""

from __future__ import annotations

import sys
from dataclasses import replace

from pedenv.config import Config
from pedenv.detection import create_detector
from pedenv.evaluation.tracking_metrics import TrackingAccumulator
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel
from pedenv.synthetic import SCENARIOS, generate_scenes

#: The tracking fields the identity changes add; "before" sets them back to the paper's.
IDENTITY_FIELDS = {"low_score_threshold": 0.0, "ground_gate": 0.0, "memory_s": 0.0}


def fused_configs() -> dict[str, Config]:
    """``before``: the fused preset as it was (no identity changes); ``after``: today's."""
    after = configure(Config(), "fused")
    data = after.to_dict()
    data["tracking"].update(IDENTITY_FIELDS)
    return {"before": Config.from_dict(data), "after": after}


def identity_metrics(scenes, config: Config, backend="detector-model") -> dict:
    """MOTA, IDF1, id switches and matched detections over ``scenes`` (per-scene summed)."""
    backend = create_detector(backend) if isinstance(backend, str) else backend
    model = PedestrianEnvironmentModel(config)
    acc = TrackingAccumulator()
    for scene in scenes:
        model.reset()
        for frame in scene.frames:
            frame = replace(frame, detections=backend(frame))
            peds = model.update(frame).pedestrians
            gt = frame.ground_truth
            if gt is not None:
                acc.add(frame.scene, gt.ids, gt.boxes, peds.track_ids, peds.boxes)
    mh = acc._mm.metrics.create()
    df = mh.compute_many(list(acc.scenes.values()), names=list(acc.scenes),
                         metrics=["mota", "idf1", "num_switches", "num_matches"], generate_overall=True)
    row = df.loc["OVERALL"]
    switches, matches = int(row["num_switches"]), int(row["num_matches"])
    return {"mota": float(row["mota"]), "idf1": float(row["idf1"]), "id_switches": switches,
            "matches": matches, "switches_per_100": 100.0 * switches / max(matches, 1),
            "per_scene": {name: int(df.loc[name, "num_switches"]) for name in acc.scenes}}


def main(duration_s: float | None = None, seed: int = 0) -> None:
    scenes = generate_scenes(seed, SCENARIOS, terrain=True, duration_s=duration_s)
    print(f"synthetic terrain scenes, seed {seed}, {sum(len(s.frames) for s in scenes)} frames, detector-model")
    print(f"{'tracker':8s} {'MOTA':>7s} {'IDF1':>7s} {'IDsw':>5s} {'matched':>8s} {'IDsw/100':>9s}")
    for name, config in fused_configs().items():
        m = identity_metrics(scenes, config)
        print(f"{name:8s} {m['mota']:7.4f} {m['idf1']:7.4f} {m['id_switches']:5d} {m['matches']:8d} "
              f"{m['switches_per_100']:9.3f}  {m['per_scene']}")


if __name__ == "__main__":
    main(float(sys.argv[1]) if len(sys.argv) > 1 else None)
