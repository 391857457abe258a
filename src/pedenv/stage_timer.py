"""Wall time of the model's stages, as the paper reports them (Sec. IV-C)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class StageTimer:
    """Accumulated wall time of the stages: tracking per frame, position per pedestrian."""

    tracking_s: float = 0.0
    frames: int = 0
    position_s: float = 0.0
    pedestrians: int = 0

    def add(self, tracking_s: float, position_s: float, pedestrians: int) -> None:
        """Count one frame: its tracking time, its position time and its pedestrians."""
        self.tracking_s += tracking_s
        self.position_s += position_s
        self.frames += 1
        self.pedestrians += pedestrians

    def per_stage_ms(self) -> dict:
        return {
            "tracking_per_frame": 1e3 * self.tracking_s / max(self.frames, 1),
            "position_per_pedestrian": 1e3 * self.position_s / max(self.pedestrians, 1),
        }
