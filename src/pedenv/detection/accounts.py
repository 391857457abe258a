"""How the ``stream`` detection spent its budget, over the frames it saw (saved in ``run.json``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from pedenv.detection.budget import FramePlan
from pedenv.detection.tiling import units


@dataclass
class StreamAccounts:
    """Counts over the frames a :class:`~pedenv.detection.stream.StreamState` saw; units are 384x640 inputs."""

    frames: int = 0
    restarts: int = 0
    cold_starts: int = 0
    units: dict[str, float] = field(default_factory=lambda: {"whole_frame": 0.0, "band_tiles": 0.0, "packed": 0.0})
    warm_units: float = 0.0
    max_units: float = 0.0
    max_units_warm: float = 0.0
    frames_over_budget: int = 0
    frames_on_credit: int = 0
    credit_units: float = 0.0
    tracks_at_risk: int = 0
    tracks_found: int = 0
    cascade_confirmed: int = 0
    tile_visits: int = 0
    tiles_late: int = 0
    band_reserve_units: float = 0.0

    def add(self, ran: tuple, plan: FramePlan, cold: bool, counts: tuple[int, int, int], late: int) -> None:
        """One frame: ``ran`` (its whole-frame pass, band tiles, packed inputs), its plan, whether a
        cold start, ``counts`` (tracks searched, found in crops, cascade confirmations) and the
        tiles it left older than the scan period."""
        first, steps, passes = ran
        at_risk, found, verified = counts
        spent = [units(first.input_size), sum(units(s.input_size) for s in steps),
                 sum(units(p.input_size) for p in passes)]
        for key, value in zip(self.units, spent):
            self.units[key] += value
        total = sum(spent)
        self.frames += 1
        self.cold_starts += int(cold)
        self.max_units = max(self.max_units, total)
        if not cold:
            self.warm_units += total
            self.max_units_warm = max(self.max_units_warm, total)
        self.frames_over_budget += int(plan.over_budget and not cold)
        self.frames_on_credit += int(not cold and not plan.over_budget and total > plan.budget + 1e-9)
        self.tracks_at_risk += at_risk
        self.tracks_found += found
        self.cascade_confirmed += verified
        self.tile_visits += len(steps)
        self.tiles_late += late
        self.band_reserve_units = plan.reserve_units

    def to_dict(self) -> dict:
        n = max(self.frames, 1)
        return {"frames": self.frames, "restarts": self.restarts, "cold_starts": self.cold_starts,
                "units_per_frame": sum(self.units.values()) / n,
                "units_per_frame_by_use": {k: v / n for k, v in self.units.items()},
                "units_per_frame_after_cold_starts": self.warm_units / max(self.frames - self.cold_starts, 1),
                "max_units_per_frame": self.max_units, "max_units_per_frame_after_cold_start": self.max_units_warm,
                "frames_past_budget_for_a_due_tile": self.frames_over_budget,
                "frames_past_budget_on_credit": self.frames_on_credit, "credit_units_left": self.credit_units,
                "band_units_per_frame_needed": self.band_reserve_units,
                "tracks_at_risk_searched": self.tracks_at_risk, "tracks_found_in_crops": self.tracks_found,
                "cascade_confirmed": self.cascade_confirmed, "tile_visits": self.tile_visits,
                "tiles_older_than_scan_period": self.tiles_late}
