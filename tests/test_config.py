import pytest

from pedenv.config import Config, PaperConfig, TrackingConfig
from pedenv.localization import configure
from pedenv.model import PedestrianEnvironmentModel


def test_defaults_are_the_papers():
    c = Config()
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
    (TrackingConfig, "max_misses", 0, "tracking.max_misses must be an integer >= 1"),
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
    fused = configure(Config(), "fused")
    assert fused.method == "fused"
    assert fused.tracking.max_height_ratio == 1.5 and fused.kalman.restart_gate == 25.0
    assert fused.tracking.predict_motion
    assert configure(Config(), "paper") == Config()
    mine = configure(Config().replace(kalman={"restart_gate": 9.0}), "fused")
    assert mine.kalman.restart_gate == 9.0
    with pytest.raises(ValueError, match="unknown position method 'magic'; valid: paper, fused"):
        configure(Config(), "magic")
    with pytest.raises(ValueError, match="unknown position method 'magic'"):
        PedestrianEnvironmentModel(Config(method="magic"))
