"""The matches of a static scene's estimates with its truth, where the paper protocol's mean comes
from and a per-person table (``benchmarks/static_cameras.py --breakdown --persons``).

The paper's protocol pairs each estimate with the nearest truth whose box overlaps its box at all,
so a fragment of a person, or someone not in the truth, counts against another person's position;
the one-to-one matches (box IoU >= 0.5) are the whole persons found, whose errors the coverages use.
"""

from __future__ import annotations

import numpy as np

from pedenv.evaluation.box_truth import truth_covariances
from pedenv.records import Frame
from pedenv.state import EnvironmentState

#: Range bins (metres from the camera to the truth) of ``--breakdown``.
RANGE_BINS_M = ((0.0, 15.0), (15.0, 30.0), (30.0, 1000.0))
#: The rows compared person by person (``--persons``).
PERSON_ROWS = ("fused vehicle", "fused static")


class Pairs:
    """Per frame the matches of a scene's estimates with its truth (``on_frame`` hook).

    one_to_one: per frame (K, 2) the relative error (%) and truth id of each box match with IoU
    >= 0.5 (whole persons found). protocol: per frame (K, 4) the paper protocol's pairs (each
    estimate with the nearest truth whose box overlaps it): relative error (%), the truth's range
    (m), 1 where that truth is the estimate's one-to-one person (else 0: a fragment or someone
    not in the truth scored against them), the truth's id. with_truth: per frame (K,) the
    one-to-one errors' Mahalanobis distances with the box-bottom truth's own covariance added
    to the reported one (:mod:`pedenv.evaluation.box_truth`), where ``box_truth`` is set (MOT17).
    """

    def __init__(self, box_truth: bool = False) -> None:
        self.box_truth = box_truth
        self.sources: list[str] = []
        self.one_to_one: list[np.ndarray] = []
        self.protocol: list[np.ndarray] = []
        self.with_truth: list[np.ndarray] = []

    def on_frame(self, state: EnvironmentState, frame: Frame) -> None:
        from pedenv.evaluation.matching import match_one_to_one, match_to_ground_truth, position_errors

        peds, truth = state.pedestrians, frame.ground_truth
        self.sources.extend(map(str, peds.sources))
        if truth is None:
            return
        ego = state.ego.translation[:2]
        pick = match_one_to_one(peds.boxes, truth.boxes)
        ok = pick >= 0
        rel = position_errors(peds.positions[ok, :2], truth.positions[pick[ok], :2], ego)[1]
        self.one_to_one.append(np.column_stack([rel, truth.ids[pick[ok]]]))
        if self.box_truth:
            e = peds.positions[ok, :2] - truth.positions[pick[ok], :2]
            cov = peds.covariances[ok] + truth_covariances(frame.camera, truth.boxes[pick[ok]],
                                                           truth.positions[pick[ok], :2])
            self.with_truth.append(np.sqrt(np.einsum("ni,nij,nj->n", e, np.linalg.inv(cov + 1e-9 * np.eye(2)), e)))
        near = match_to_ground_truth(peds.boxes, peds.positions[:, :2], truth.boxes, truth.positions[:, :2])
        hit = near >= 0
        _, rel, dist = position_errors(peds.positions[hit, :2], truth.positions[near[hit], :2], ego)
        self.protocol.append(np.column_stack([rel, dist, near[hit] == pick[hit], truth.ids[near[hit]]]))

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """(one-to-one (K, 2), protocol (K, 4)) over the scene (class notes)."""
        return (np.concatenate(self.one_to_one) if self.one_to_one else np.zeros((0, 2)),
                np.concatenate(self.protocol) if self.protocol else np.zeros((0, 4)))


def coverage_with_truth(distances: list[np.ndarray]) -> dict:
    """The 1- and 2-sigma coverages (%) of the per-frame Mahalanobis distances with the truth's
    own covariance added (:class:`Pairs`); empty without a box-bottom truth."""
    m = np.concatenate(distances) if distances else np.zeros(0)
    if not len(m):
        return {}
    return {"within_1sigma_with_truth": round(100 * float(np.mean(m <= 1.0)), 1),
            "within_2sigma_with_truth": round(100 * float(np.mean(m <= 2.0)), 1)}


def persons(one: np.ndarray, protocol: np.ndarray, total: int) -> dict:
    """Per truth id (and its median range, m): ``one_to_one`` ``[count, mean rel. error %]`` of its
    whole-person matches, and the paper protocol's pairs scored against it, ``own`` (its own
    whole-person estimate) and ``others`` (a fragment or someone not in the truth), each
    ``[count, mean rel. error %, points of the scene's protocol mean]``. Arrays as :class:`Pairs`."""
    def group(rel: np.ndarray, share: bool = True) -> list:
        mean = round(float(rel.mean()), 2) if len(rel) else float("nan")
        return [len(rel), mean] + ([round(float(rel.sum()) / max(total, 1), 2)] if share else [])

    out = {}
    for pid in np.unique(np.concatenate([one[:, 1], protocol[:, 3]])).astype(int):
        mine = protocol[protocol[:, 3] == pid]
        own = mine[:, 2] > 0
        out[int(pid)] = {"range_m": round(float(np.median(mine[:, 1])), 1) if len(mine) else float("nan"),
                         "one_to_one": group(one[one[:, 1] == pid, 0], share=False),
                         "own": group(mine[own, 0]), "others": group(mine[~own, 0])}
    return out


def breakdown(matches: np.ndarray) -> dict:
    """Where the paper-protocol mean comes from. matches: (K, 3) per match its relative error
    (%), the truth's range (m) and 1 where the truth is the estimate's one-to-one person (a whole
    person found), 0 where it is the nearest overlapping truth of a fragment or of someone not
    in the truth. Per group ``[count, mean rel. error %, points of the overall mean]``."""
    rel, dist, whole = matches[:, 0], matches[:, 1], matches[:, 2] > 0
    total = max(len(rel), 1)

    def group(mask: np.ndarray) -> list:
        return [int(mask.sum()), round(float(rel[mask].mean()), 2) if mask.any() else float("nan"),
                round(float(rel[mask].sum()) / total, 2)]

    out = {"whole persons": group(whole), "others": group(~whole)}
    for low, high in RANGE_BINS_M:
        out[f"{low:g}-{high:g} m"] = group((dist >= low) & (dist < high))
    return out


def print_persons(label: str, results: dict[str, dict]) -> None:
    """A per-person table of one scene comparing the fused rows of ``results`` (row label -> the
    figures of :func:`evaluate`): per truth id its one-to-one matches and the paper protocol's
    pairs scored against it (:func:`persons`), then the totals of the protocol's two kinds."""
    names = [n for n in PERSON_ROWS if n in results]
    print(f"\n{label}: per person, [count, mean rel. error %] one-to-one; protocol pairs against the person "
          "[count, mean %, points of the scene's mean], own estimate | others")
    print("| id | range m | " + " | ".join(f"{n}: one-to-one | own | others" for n in names) + " |")
    print("|---|---|" + "---|---|---|" * len(names))
    ids = sorted({i for n in names for i in results[n]["persons"]},
                 key=lambda i: min(results[n]["persons"].get(i, {}).get("range_m", np.inf) for n in names))
    for pid in ids:
        cells, rng = [], float("nan")
        for n in names:
            row = results[n]["persons"].get(pid)
            if row is None:
                cells += ["-", "-", "-"]
                continue
            rng = row["range_m"] if rng != rng else rng
            cells += [str(row["one_to_one"]), str(row["own"]), str(row["others"])]
        print(f"| {pid} | {rng:.1f} | " + " | ".join(cells) + " |")
    totals = []
    for n in names:
        b = results[n]["breakdown"]
        totals += [f"{results[n]['rel_error_one_to_one_pct']:.2f} % ({results[n]['count_one_to_one']})",
                   str(b["whole persons"]), str(b["others"])]
    print("| all | | " + " | ".join(totals) + " |", flush=True)
