"""Which cues made each fused estimate and why the others did not: flags, spelled at the output.

The fusion leaves per pedestrian and cue whether the cue was used, outvoted by the gate or
degenerate, and the cue's own reason for declining (:data:`~pedenv.localization.fused.cue.REASONS`);
a pedestrian no cue placed is guessed from its box. :class:`CueSources` keeps these as
flags; :meth:`CueSources.spell` writes the ``sources`` text of the measurement: the used
cues joined by ``+``, then ``;cue:reason`` for each cue left out, the name ``box`` in
front where the box placed the pedestrian, e.g. ``ground+height;triangulation:no-baseline``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pedenv.localization.fused.cue import REASONS, CueEstimate
from pedenv.localization.fused.fusion import Fused


@dataclass(frozen=True)
class CueSources:
    """The cues behind N estimates, as flags.

    names: the C cues, in fusion order. used, outvoted, degenerate: (N, C) bool, as in
    :class:`~pedenv.localization.fused.fusion.Fused`. reasons: (N, C) int, the code of why
    each cue declined (0 where it did not). boxed: (N,) bool, no cue placed the pedestrian
    and its box did.
    """

    names: tuple[str, ...]
    used: np.ndarray
    outvoted: np.ndarray
    degenerate: np.ndarray
    reasons: np.ndarray
    boxed: np.ndarray

    @classmethod
    def of(cls, cues: list[CueEstimate], fused: Fused, boxed: np.ndarray) -> CueSources:
        """The flags of the ``cues`` fused into ``fused``; ``boxed`` (N,) bool."""
        return cls(tuple(q.name for q in cues), fused.used, fused.outvoted, fused.degenerate,
                   np.stack([q.reasons for q in cues], axis=1), np.asarray(boxed, bool))

    def spell(self) -> np.ndarray:
        """(N,) str, each estimate's ``sources`` text (module notes); each distinct
        combination of flags (a few a frame) is spelled once."""
        # one row per estimate: boxed, then C flags each of used, outvoted, degenerate, reasons
        flags = np.column_stack([self.boxed, self.used, self.outvoted, self.degenerate, self.reasons])
        rows = [tuple(row) for row in flags.astype(np.int64).tolist()]
        texts = {row: self._spell_row(row) for row in set(rows)}
        return np.array([texts[row] for row in rows])

    def _spell_row(self, row: tuple[int, ...]) -> str:
        c = len(self.names)
        used, outvoted, degenerate, reasons = (row[1 + i * c:1 + (i + 1) * c] for i in range(4))
        return spell_one(self.names, bool(row[0]), used, outvoted, degenerate, reasons)


def spell_one(names: tuple[str, ...], boxed: bool, used: Sequence[int], outvoted: Sequence[int],
              degenerate: Sequence[int], reasons: Sequence[int]) -> str:
    """One estimate's ``sources`` text from its flags: one entry per cue in each list."""
    head = "+".join(name for name, u in zip(names, used) if u)
    why = [left_out_reason(*flags) for flags in zip(used, outvoted, degenerate, reasons)]
    tail = "".join(f";{name}:{w}" for name, w in zip(names, why) if w)
    return ("box" if boxed else "") + head + tail


def left_out_reason(used: int, outvoted: int, degenerate: int, reason: int) -> str:
    """Why a cue is not in an estimate (flags 0 or 1, a reason code): ``outvoted`` by the gate,
    ``degenerate`` numbers, else its own reason; empty where it was used (or declined without one)."""
    if used:
        return ""
    if outvoted:
        return "outvoted"
    return "degenerate" if degenerate else REASONS[reason]
