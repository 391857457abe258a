"""YAML and JSON from users: limits on size, nesting and alias expansion, one error line
naming the file and never holding the document's values."""

from __future__ import annotations

import tracemalloc

import pytest

from pedenv import structured_text
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.recordings.footage import load_calibration
from pedenv.recordings.manifest import read_manifest
from pedenv.structured_text import MAX_DEPTH, load_json, load_yaml, parse_json, parse_yaml


def alias_bomb(levels: int = 9, width: int = 9) -> str:
    """``levels`` lists of ``width`` aliases of the list before: ``width ** levels`` values."""
    lines = ["a0: &a0 [" + ", ".join(["x"] * width) + "]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * width) + "]" for i in range(1, levels + 1)]
    return "\n".join(lines) + f"\nfx: *a{levels}\n"


def test_an_alias_bomb_is_refused_without_building_it(tmp_path):
    path = tmp_path / "calib.yaml"
    path.write_text(alias_bomb())
    assert path.stat().st_size < 700  # 387 million values once expanded
    tracemalloc.start()
    with pytest.raises(InputError) as info:
        load_calibration(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert str(info.value) == f"{path}: the calibration expands to more than 1,000,000 values (YAML aliases?)"
    assert peak < 20e6


def test_a_long_string_repeated_by_aliases_counts_its_length(tmp_path):
    text = "s: &s " + "x" * 200_000 + "\nl: [" + ", ".join(["*s"] * 600) + "]\n"  # 120 MB once repeated
    with pytest.raises(InputError, match="expands to more than"):
        parse_yaml(text, "big.yaml")


def test_anchors_of_a_normal_file_are_fine():
    text = "base: &b {calibration: calib.yaml, fps: 10}\nrecordings:\n  - *b\n  - *b\n"
    assert parse_yaml(text, "m.yaml")["recordings"] == [{"calibration": "calib.yaml", "fps": 10}] * 2


def test_a_recursive_alias_is_refused():
    with pytest.raises(InputError, match=r"m.yaml: the manifest holds a recursive YAML alias \(\*a\)"):
        parse_yaml("a: &a [1, *a]\n", "m.yaml", "the manifest")


@pytest.mark.parametrize("suffix, text", [
    (".json", "[" * 50000), (".json", "[" * 50000 + "]" * 50000), (".json", '{"a": ' * 100 + "1" + "}" * 100),
    (".yaml", "[" * 50000), (".yaml", "- " * 100 + "1\n"), (".yaml", "a:\n" + "".join(" " * i + "b:\n" for i in
                                                                                     range(1, 100))),
])
def test_deep_nesting_is_one_line_not_a_recursion_error(tmp_path, suffix, text):
    path = tmp_path / f"deep{suffix}"
    path.write_text(text)
    load = load_json if suffix == ".json" else load_yaml
    with pytest.raises(InputError) as info:
        load(path, "the config")
    assert str(info.value) == f"{path}: the config is nested deeper than {MAX_DEPTH} levels"


def test_nesting_up_to_the_limit_is_read():
    assert isinstance(parse_json("[" * MAX_DEPTH + "]" * MAX_DEPTH, "ok.json"), list)
    assert isinstance(parse_yaml("[" * MAX_DEPTH + "]" * MAX_DEPTH, "ok.yaml"), list)


def test_a_large_file_is_refused_before_it_is_read(tmp_path, monkeypatch):
    monkeypatch.setattr(structured_text, "MAX_BYTES", 1000)
    path = tmp_path / "big.json"
    path.write_text("[" + "1, " * 500 + "1]")
    with pytest.raises(InputError, match=r"big.json: the config is larger than 1,000 bytes"):
        Config.load(path)


@pytest.mark.parametrize("text, message", [
    ("a: [1, 2\n", r"bad.yaml: not valid YAML \(line 2, column 1: expected ',' or ']', but got '<stream end>'\)"),
    ("a: 1\n---\nb: 2\n", "bad.yaml: not valid YAML"),
    ("\tx: 1\n", "bad.yaml: not valid YAML"),
])
def test_invalid_yaml_names_the_file_and_line(text, message):
    with pytest.raises(InputError, match=message):
        parse_yaml(text, "bad.yaml")


def test_invalid_json_names_the_file_and_line():
    with pytest.raises(InputError, match=r"bad.json: the config is not valid JSON \(line 1, column 11"):
        parse_json('{"paper": tru}', "bad.json", "the config")


def test_the_manifest_goes_through_the_limits(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(alias_bomb(8, 9))
    with pytest.raises(InputError, match=r"m.yaml: the manifest expands to more than"):
        read_manifest(path)
    path.write_text("[" * 50000)
    with pytest.raises(InputError, match=r"m.yaml: the manifest is nested deeper than"):
        read_manifest(path)
