"""Config.behaviour: the fused preset turns it on, the paper's method has none; bad values name the field."""

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
    ("width_ratio_std", -1.0, "behaviour.width_ratio_std"),
    ("conflict_probability", 1.0, "behaviour.conflict_probability"),
    ("horizons_s", (2.0, 1.0), "behaviour.horizons_s"),
    ("horizons_s", (0.5, float("nan")), "behaviour.horizons_s"),
    ("walk_exit_mps", 0.9, "walk_exit_mps < walk_enter_mps"),
    ("conflict_step_s", 0.9, "behaviour.conflict_step_s"),
    ("max_ego_gap_s", float("nan"), "behaviour.max_ego_gap_s"),
    ("ego_trend_s", -0.5, "behaviour.ego_trend_s"),
    ("max_ego_jerk_mps3", 100.0, "behaviour.max_ego_jerk_mps3"),
    ("max_pedestrian_speed_mps", 0.1, "behaviour.max_pedestrian_speed_mps"),
])
def test_bad_values_name_the_field(field, value, message):
    kwargs = {field: value}
    if field == "conflict_step_s":
        kwargs["conflict_horizon_s"] = 0.5
    with pytest.raises(InputError, match=message.replace(".", r"\.").replace("<", "<")):
        BehaviourConfig(**kwargs)
