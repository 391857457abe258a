"""Config.behaviour: the fused preset turns it on, the paper's method has none; bad values name the field."""

import re

import pytest

from pedenv.behaviour.config import BehaviourConfig
from pedenv.config import Config
from pedenv.errors import InputError


def test_on_in_fused_off_in_paper_and_round_trips():
    assert Config().behaviour.enabled and not Config(method="paper").behaviour.enabled
    cfg = Config().replace(behaviour={"horizons_s": [0.5, 1.5], "corridor_half_width_m": 2.0})
    again = Config.from_dict(cfg.to_dict())
    assert again.behaviour.horizons_s == (0.5, 1.5) and again.behaviour.corridor_half_width_m == 2.0


@pytest.mark.parametrize("field, value, message", [
    ("enabled", "yes", "behaviour.enabled"),
    ("orientation_bins", 5, "behaviour.orientation_bins"),
    ("orientation_interval_s", -0.1, "behaviour.orientation_interval_s"),
    ("orientation_interval_s", float("inf"), "behaviour.orientation_interval_s"),
    ("available_std_deg", 0.5, "behaviour.available_std_deg"),
    ("corridor_half_width_m", 0.0, "behaviour.corridor_half_width_m"),
    ("horizons_s", (2.0, 1.0), "behaviour.horizons_s"),
    ("horizons_s", (0.5, float("nan")), "behaviour.horizons_s"),
    ("walk_exit_mps", 0.9, "behaviour.walk_exit_mps (0.9) must be below behaviour.walk_enter_mps (0.45)"),
    ("walk_enter_mps", 0.25, "behaviour.walk_exit_mps (0.3) must be below behaviour.walk_enter_mps (0.25)"),
    ("walk_enter_mps", 2.5, "behaviour.walk_enter_mps (2.5) must not exceed behaviour.run_exit_mps (2.3)"),
    ("run_exit_mps", 0.4, "behaviour.walk_enter_mps (0.45) must not exceed behaviour.run_exit_mps (0.4)"),
    ("run_enter_mps", 2.0, "behaviour.run_exit_mps (2.3) must be below behaviour.run_enter_mps (2.0)"),
    ("conflict_horizon_s", 0.05, "behaviour.conflict_horizon_s"),
])
def test_bad_values_name_the_field(field, value, message):
    with pytest.raises(InputError, match=re.escape(message)):
        BehaviourConfig(**{field: value})


def test_the_motion_thresholds_may_move_together():
    """Thresholds that keep their order are accepted wherever they lie in their ranges."""
    cfg = BehaviourConfig(walk_exit_mps=1.0, walk_enter_mps=1.2, run_exit_mps=1.2, run_enter_mps=4.0)
    assert (cfg.walk_exit_mps, cfg.run_enter_mps) == (1.0, 4.0)
