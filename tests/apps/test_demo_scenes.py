"""Built-in scenes are made one at a time (issue 10.7: simulate --scenes 10000 held them all)."""

from __future__ import annotations

import pytest

import pedenv.synthetic as synthetic
from pedenv.apps.demo import MAX_SCENES, builtin_scenes, iter_builtin_scenes
from pedenv.errors import InputError


def test_scenes_are_generated_lazily_and_match_the_list(monkeypatch):
    made = []
    real = synthetic.generate_scenes

    def counting(seed, names=None, **kw):
        made.extend(names or [])
        return real(seed, names, **kw)

    monkeypatch.setattr(synthetic, "generate_scenes", counting)
    stream = iter_builtin_scenes(4, 9, frame_rate_hz=0.5)
    assert made == []  # options checked, nothing generated yet
    first = next(stream)
    assert len(made) == 1 and first.name == "red-light-crossing"
    rest = list(stream)
    assert [s.name for s in rest][-2:] == ["red-light-crossing-1", "drive-30kmh-sidewalk-1"]
    again = builtin_scenes(4, 9, frame_rate_hz=0.5)
    assert [s.name for s in again] == [first.name] + [s.name for s in rest]
    assert again[7].frames[2].ground_truth.positions.tolist() == rest[6].frames[2].ground_truth.positions.tolist()


@pytest.mark.parametrize("count", [0, MAX_SCENES + 1, 2.5, True])
def test_scene_count_is_bounded(count):
    with pytest.raises(InputError, match=rf"number of scenes must be an integer in \[1, {MAX_SCENES}\]"):
        iter_builtin_scenes(0, count)
