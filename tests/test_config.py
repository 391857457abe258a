import dataclasses
import json

import pytest

from pedenv.apps.run import detection_mode
from pedenv.config import (
    DEFAULT_METHOD,
    METHOD_PRESETS,
    SECTIONS,
    Config,
    KalmanConfig,
    PaperConfig,
    TrackingConfig,
)
from pedenv.detection import DetectionConfig, backend_options
from pedenv.errors import InputError
from pedenv.localization import LOCATORS, configure

from cli_in_process import pedenv


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
    with pytest.raises(ValueError, match="unknown position method 'magic'; valid: paper, fused"):
        Config(method="magic")  # refused where it is made, not later by the model
    assert set(METHOD_PRESETS) == set(LOCATORS)  # the methods Config accepts are those that exist


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


# Issue 19 (items 4 and 5): each bad value in a config is one clear error naming section.field.
@pytest.mark.parametrize("data, message", [
    ({"paper": {"refinement_steps": 1000000000}},
     r"paper.refinement_steps must be an integer in [0, 200], got 1000000000"),
    ({"fused": {"history_length": 10 ** 12}}, "fused.history_length must be an integer in [1, 100], got 1000000000000"),
    ({"tracking": {"max_misses": 1e9}}, "tracking.max_misses must be an integer in [1, 300], got 1000000000.0"),
    ({"method": "paper", "paper": {"person_height_m": float("nan")}},
     "paper.person_height_m must be a finite number, got nan"),
    ({"fused": {"max_range_m": float("nan")}}, "fused.max_range_m must be a finite number, got nan"),
    ({"fused": {"max_range_m": float("inf")}}, "fused.max_range_m must be a finite number, got inf"),
    ({"paper": {"refine": "false"}}, "paper.refine must be true or false, got 'false'"),
    ({"kalman": {"enabled": 0}}, "kalman.enabled must be true or false, got 0"),
    ({"tracking": {"yaw_compensation": "yes"}}, "tracking.yaw_compensation must be true or false, got 'yes'"),
    ({"tracking": {"giou_threshold": True}}, "tracking.giou_threshold must be a number, got True"),
    ({"tracking": {"low_score_threshold": 0.3}},
     "tracking.low_score_threshold must be 0.0 (off) or in (0.0, 0.25], got 0.3"),
    ({"kalman": {"restart_gate": 1e300}}, "kalman.restart_gate must be in [0.0, 10000.0], got 1e+300"),
    ({"fused": {"cues": ["ground", "x" * 10 ** 6]}},
     f"fused.cues entry must be one of ground, triangulation, height, got '{'x' * 27}...{'x' * 28}'"),
    ({"fused": {"cues": list(range(10 ** 6))}},
     "fused.cues must list at least one and at most 3 entries, got (0, 1, 2, 3, ...)"),
    ({"detection": {"mode": "slow"}}, "detection.mode must be one of fast, far, stream, got 'slow'"),
    ({"detection": {"level_scales": [1.0, 2.0] * 10}},
     "detection.level_scales must be a non-empty tuple of at most 8 numbers, got (1.0, 2.0, 1.0, 2.0, ...)"),
    ({"detection": {"tile_width": 1e9}}, "detection.tile_width must be an integer in [160, 4096], got 1000000000.0"),
    ({"merge": {"oks": float("nan")}}, "merge.oks is no longer a setting (fixed at 0.3); remove it from the config, "
                                      "got nan"),
    ({"redetect": {"max_crops": 10 ** 9}}, "redetect.max_crops must be an integer in [0, 64], got 1000000000"),
    ({"method": ["fused"] * 10 ** 6}, "method must be the name of a position method, got ['fused', 'fused', 'fused', "
                                      "'fused', ...]"),
    ({"paper": [1, 2]}, "config.paper must be an object of fields, got list"),
    ({f"s{i}": {} for i in range(1000)}, "unknown config section(s): s0, s1, s10, s100, s101 and 995 more; "
                                         f"valid: method, {', '.join(SECTIONS)}"),
])
def test_bad_config_values_give_one_clear_error(data, message):
    with pytest.raises(InputError) as info:
        Config.from_dict(data)
    assert str(info.value) == message


def _bad_values(value):
    """Values of the wrong type, not finite or beyond any documented bound, for a field holding ``value``."""
    if isinstance(value, bool):
        return ["false", 1, None]
    if isinstance(value, (int, float)):
        return [float("nan"), float("inf"), 1e300, "1", True, None]
    return [1e300, None]


@pytest.mark.parametrize("section", list(SECTIONS))
def test_every_field_checks_type_finiteness_and_an_upper_bound(section):
    """Every value of every section: the wrong type, NaN, inf and 1e300 are refused, naming section.field."""
    defaults = getattr(Config(), section)
    for field in dataclasses.fields(defaults):
        for bad in _bad_values(getattr(defaults, field.name)):
            with pytest.raises(InputError, match=rf"^{section}\.{field.name}"):
                Config.from_dict({section: {field.name: bad}})


def test_every_setting_of_a_run_round_trips_through_config_json(tmp_path):
    changed = {"tracking": {"max_misses": 7, "yaw_compensation": False}, "paper": {"refine": False},
               "kalman": {"restart_gate": 9.0}, "fused": {"cues": ["ground", "height"], "history_length": 10},
               "redetect": {"max_crops": 2}, "detection": {"mode": "fast", "level_scales": [1.0, 1.5, 3.0],
                                                           "tile_width": 1280, "near_m": 3.0}}
    cfg = Config().replace(**changed)
    cfg.save(tmp_path / "config.json")
    saved = json.loads((tmp_path / "config.json").read_text())
    assert set(saved) == {"method", *SECTIONS} >= {"detection", "redetect"}
    assert saved["detection"]["level_scales"] == [1.0, 1.5, 3.0] and saved["redetect"]["max_crops"] == 2
    loaded = Config.load(tmp_path / "config.json")
    assert loaded == cfg
    assert loaded.detection == DetectionConfig(mode="fast", level_scales=(1.0, 1.5, 3.0), tile_width=1280, near_m=3.0)
    assert loaded.fused.cues == ("ground", "height")
    for section, values in changed.items():  # every field changed above comes back as set
        for name, value in values.items():
            assert getattr(getattr(loaded, section), name) == (tuple(value) if isinstance(value, list) else value)


def test_a_config_saved_before_detection_loads_its_defaults(tmp_path):
    data = Config().to_dict()
    del data["detection"]
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = Config.load(tmp_path / "old.json")
    assert old == Config() and old.detection == DetectionConfig()


def test_a_config_with_settings_that_became_constants_loads_when_they_hold_their_fixed_values(tmp_path):
    """config.json files saved before the detection settings were cut to what a user turns: the
    fields that became constants load when they hold today's values (so nothing changes), another
    value is refused naming the field; the old names of the packed input's size still load."""
    data = Config().to_dict()
    data["merge"] = {"iou": 0.5, "containment": 0.7, "oks": 0.3, "keypoint_min_confidence": 0.3}
    data["detection"].update(tile_overlap=0.25, max_tiles=12, fit_min_score=0.35)
    data["detection"]["stream"].update(crop_min_width=0.0, trim_mosaics=True, mosaic_width=512)
    data["redetect"].update(crop_scale=2.0, min_hits=2)
    (tmp_path / "old.json").write_text(json.dumps(data))
    old = Config.load(tmp_path / "old.json")
    assert old.detection.stream.packed_width == 512
    assert old == Config().replace(detection={"stream": {"packed_width": 512}})
    for section, field, value in (("detection", "max_tiles", 6), ("redetect", "min_hits", 3), ("merge", "iou", 0.4)):
        changed = Config().to_dict() | {"merge": {}}
        changed[section][field] = value
        with pytest.raises(InputError, match=rf"{section}\.{field} is no longer a setting \(fixed at"):
            Config.from_dict(changed)
    with pytest.raises(InputError, match=r"detection.stream.crop_min_width is no longer a setting"):
        Config.from_dict({"detection": {"stream": {"crop_min_width": 0.6}}})


@pytest.mark.parametrize("width", [128, 160, 1280])
def test_an_accepted_packed_input_width_plans_the_band_without_an_error(width):
    """Issue 32: ``detection.stream.packed_width`` 128 was accepted, then every ``stream`` frame
    stopped on ``detection.tile_width`` (a field the user never set): the band's tiles now take the
    packed input's width as it is."""
    from pedenv.detection.budget import band_tiles
    from pedenv.detection.geometry import CameraGeometry
    from pedenv.records import Camera

    cfg = Config.from_dict({"detection": {"mode": "stream", "stream": {"packed_width": width}}})
    tiles, note = band_tiles(1600, 900, cfg.detection, CameraGeometry.level(Camera.from_fov().intrinsics, 1.5), None)
    assert tiles and "calibration" in note
    assert max(t.step.input_size[1] for t in tiles) <= width + 32  # a tile's px rounded up to the stride


def test_the_commands_detection_mode_is_recorded_in_the_config():
    cfg = Config().replace(detection={"tile_width": 1280})
    assert detection_mode(cfg, "onnx", "fast").detection == DetectionConfig(mode="fast", tile_width=1280)
    assert detection_mode(cfg, "onnx", None) == cfg
    assert detection_mode(cfg, "ground-truth", "fast") == cfg
    options = backend_options("onnx", None, None, cfg.detection, None, redetect=cfg.redetect)
    assert options["detection"] is cfg.detection and options["redetect"] is cfg.redetect


@pytest.mark.parametrize("text, fragment", [
    ('{"method": "paper", "paper": {"person_height_m": NaN}}',
     "paper.person_height_m must be a finite number, got nan"),
    ('{"fused": {"max_range_m": Infinity}}', "fused.max_range_m must be a finite number, got inf"),
    ('{"paper": {"refine": "false"}}', "paper.refine must be true or false, got 'false'"),
    ('{"paper": {"refinement_steps": 1000000000}}', "paper.refinement_steps must be an integer in [0, 200]"),
    ("[" * 50000, "the config is nested deeper than 64 levels"),
])
def test_a_bad_config_file_is_one_error_line_exit_2(monkeypatch, capsys, tmp_path, text, fragment):
    path = tmp_path / "bad.json"
    path.write_text(text)
    code, _, err = pedenv(monkeypatch, capsys, "demo", "--config", path, "--output", tmp_path / "o")
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith(f"error: {path}: {fragment}"), err
    assert not (tmp_path / "o").exists()
