import json

import pytest

from pedenv.config import DEFAULT_METHOD, Config, KalmanConfig, PaperConfig, TrackingConfig
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel


def test_paper_defaults_are_the_papers():
    c = Config(method="paper")
    assert c.tracking.giou_threshold == -0.3 and c.tracking.max_misses == 3
    p = c.paper
    assert (p.low_confidence_fraction, p.person_height_m, p.refinement_steps, p.refinement_lambda_offset) == (
        0.3,
        1.7,
        15,
        5.0,
    )


@pytest.mark.parametrize("kind, field, value, message", [
    (TrackingConfig, "giou_threshold", 1.0, r"tracking.giou_threshold must be in \[-1.0, 1.0\)"),
    (TrackingConfig, "max_misses", 0, r"tracking.max_misses must be an integer in \[1, 300\]"),
    (PaperConfig, "low_confidence_fraction", 1.0, "paper.low_confidence_fraction"),
    (PaperConfig, "person_height_m", 3.0, "paper.person_height_m"),
    (PaperConfig, "refinement_steps", -1, "paper.refinement_steps"),
    (PaperConfig, "initial_estimate", "centroid", "paper.initial_estimate must be one of"),
])
def test_out_of_range_values_are_refused(kind, field, value, message):
    with pytest.raises(ValueError, match=message):
        kind(**{field: value})


def test_round_trip_and_replace(tmp_path):
    c = Config().replace(paper={"refine": False}, tracking={"max_misses": 5})
    c.save(tmp_path / "config.json")
    assert Config.load(tmp_path / "config.json") == c
    with pytest.raises(ValueError, match="unknown field"):
        Config.from_dict({"tracking": {"giou": 0.1}})


def test_method_presets_fill_only_defaults():
    paper = Config(method="paper")
    fused = configure(paper, "fused")
    assert fused.method == "fused"
    assert fused.tracking.max_height_ratio == 1.5 and fused.kalman.restart_gate == 25.0
    assert fused.tracking.predict_motion
    assert configure(fused, "paper") == paper
    assert paper.tracking.max_height_ratio == 0.0 and not paper.tracking.predict_motion
    assert paper.kalman.restart_gate == KalmanConfig().restart_gate != 25.0
    mine = configure(paper.replace(kalman={"restart_gate": 9.0}), "fused")
    assert mine.kalman.restart_gate == 9.0
    assert configure(mine, "paper").kalman.restart_gate == 9.0
    with pytest.raises(ValueError, match="unknown position method 'magic'; valid: paper, fused"):
        configure(Config(), "magic")
    with pytest.raises(ValueError, match="unknown position method 'magic'"):
        PedestrianEnvironmentModel(Config(method="magic"))


def test_the_default_is_the_fused_method_as_the_commands_run_it():
    assert DEFAULT_METHOD == "fused"
    assert Config().method == "fused"
    assert Config() == configure(Config(method="paper"), "fused") == Config.from_dict({"method": "fused"})
    assert configure(Config(), "fused") == Config()
    # a field set on purpose survives a round trip through replace and the file
    no_motion = Config().replace(tracking={"predict_motion": False})
    assert not no_motion.tracking.predict_motion and no_motion.tracking.memory_s == 2.0


def test_a_saved_config_without_a_method_loads_as_fused(tmp_path):
    data = Config(method="paper").to_dict()
    del data["method"]
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = Config.load(tmp_path / "old.json")
    assert old.method == "fused"
    assert old.tracking == Config(method="paper").tracking  # the fields it names keep their values
    (tmp_path / "bare.json").write_text("{}")
    assert Config.load(tmp_path / "bare.json") == Config()


def test_a_partial_section_starts_from_its_methods_defaults():
    paper = Config.from_dict({"method": "paper", "tracking": {"max_misses": 5}})
    assert paper.tracking == TrackingConfig(max_misses=5)
    fused = Config.from_dict({"tracking": {"max_misses": 5}})
    assert fused.tracking.max_misses == 5 and fused.tracking.predict_motion and fused.tracking.memory_s == 2.0
