"""No code runs from any file pedenv reads or resumes from (issue 19).

A payload that creates a marker file when unpickled (or built by an unsafe YAML loader) is
planted in every kind of file pedenv loads: scene checkpoints (``--resume``), CARLA
``.npy`` frames, stored synthetic scenes, ``.npz`` detection caches, calibration and
manifest YAML, JSON configs. Each gives a clear error (or, for the benchmarks' caches,
numpy's refusal) and the marker never appears. A control case shows the payload is live:
the unsafe loaders do create the marker. (Model weights: ``tests/pose/test_ultralytics_weights.py``.)
"""

from __future__ import annotations

import io
import json
import pickle
from pathlib import Path

import numpy as np
import pytest
import yaml

from pedenv.apps.distributed import SCENES_FOLDER, SceneStore
from pedenv.apps.scene_checkpoint import run_identity
from pedenv.config import Config
from pedenv.datasets.carla import load_record
from pedenv.errors import InputError
from pedenv.outputs.output_dir import MARKER
from pedenv.recordings.footage import load_calibration
from pedenv.recordings.manifest import read_manifest
from pedenv.synthetic import SCENARIOS, generate_scenes
from pedenv.synthetic.storage import read_scene, write_scenes

from cli_in_process import pedenv


class Payload:
    """Unpickled, it opens ``marker`` for writing: the file appears."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return open, (self.marker, "w")


def pickled(marker: Path) -> bytes:
    return pickle.dumps({"frame": Payload(marker)})


def npz_with_payload(marker: Path, name: str = "meta") -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **{name: np.array([Payload(marker)], dtype=object)})
    return buf.getvalue()


def yaml_payload(marker: Path) -> str:
    return f"!!python/object/apply:builtins.open [{str(marker)!r}, w]\n"


def test_the_payloads_are_live(tmp_path):
    pickle.loads(pickled(tmp_path / "a"))  # noqa: S301 - the control: an unsafe loader runs it
    yaml.unsafe_load(yaml_payload(tmp_path / "b"))
    np.load(io.BytesIO(npz_with_payload(tmp_path / "c")), allow_pickle=True)["meta"]  # noqa: B018
    assert (tmp_path / "a").exists() and (tmp_path / "b").exists() and (tmp_path / "c").exists()


@pytest.mark.parametrize("planted, expected", [
    ("result.npz: pickle", "not a pedenv scene checkpoint"),
    ("result.npz: npz with an object array", "not a pedenv scene checkpoint"),
    ("result.pkl: pickle", "a checkpoint of an older pedenv, a Python pickle, which pedenv no longer opens"),
])
def test_a_forged_checkpoint_runs_no_code(tmp_path, planted, expected):
    marker = tmp_path / "ran"
    folder = tmp_path / "out" / SCENES_FOLDER / "scene-a"
    folder.mkdir(parents=True)
    (folder / "environment.jsonl").write_text("")
    name, kind = planted.split(": ")
    data = pickled(marker) if kind == "pickle" else npz_with_payload(marker)
    (folder / name).write_bytes(data)
    with pytest.raises(InputError, match=f"{folder / name}: {expected}.*scene-a"):
        SceneStore(tmp_path / "out", run_identity("synthetic", "detector-model", Config().to_dict())).load(["scene-a"])
    assert not marker.exists()


@pytest.fixture(scope="module")
def one_stored_scene(tmp_path_factory):
    root = tmp_path_factory.mktemp("scenes")
    write_scenes(generate_scenes(0, [SCENARIOS[0]], duration_s=1.0), root)
    return root


def test_evaluate_resume_of_a_forged_folder_is_one_line_and_runs_no_code(monkeypatch, capsys, tmp_path,
                                                                           one_stored_scene):
    """The issue's attack: a forged .pedenv-output, an empty environment.jsonl, a crafted pickle."""
    marker, out = tmp_path / "ran", tmp_path / "out"
    name = next(p.name for p in one_stored_scene.iterdir() if p.is_dir())
    folder = out / SCENES_FOLDER / name
    folder.mkdir(parents=True)
    (out / MARKER).write_text("")
    (folder / "environment.jsonl").write_text("")
    for checkpoint in ("result.pkl", "result.npz"):
        (folder / checkpoint).write_bytes(pickled(marker))
        code, _, err = pedenv(monkeypatch, capsys, "evaluate", "--dataset", "synthetic", "--data-root",
                              one_stored_scene, "--output", out, "--resume")
        assert code == 2 and err.startswith(f"error: {folder / checkpoint}: ") and err.count("\n") == 1, err
        assert not marker.exists()


def test_a_carla_frame_naming_a_function_runs_no_code(tmp_path):
    marker, path = tmp_path / "ran", tmp_path / "data_000001.npy"
    np.save(path, np.array(Payload(marker), dtype=object), allow_pickle=True)
    with pytest.raises(InputError, match=f"{path}: not a readable .npy file .*refusing to load"):
        load_record(path)
    assert not marker.exists()


def test_a_stored_scene_with_an_object_array_runs_no_code(tmp_path, one_stored_scene):
    marker = tmp_path / "ran"
    scene = next(p for p in one_stored_scene.iterdir() if p.is_dir())
    forged = tmp_path / scene.name
    forged.mkdir()
    (forged / "scene.json").write_text((scene / "scene.json").read_text())
    (forged / "frames.npz").write_bytes(npz_with_payload(marker, "index"))
    with pytest.raises(InputError, match=f"{forged / 'frames.npz'}: cannot read.*allow_pickle"):
        read_scene(forged)
    assert not marker.exists()


@pytest.mark.parametrize("reader, suffix", [(load_calibration, ".yaml"), (read_manifest, ".yaml"),
                                            (read_manifest, ".yml")])
def test_yaml_with_a_python_tag_runs_no_code(tmp_path, reader, suffix):
    marker, path = tmp_path / "ran", tmp_path / f"input{suffix}"
    path.write_text(yaml_payload(marker))
    with pytest.raises(InputError, match=f"{path}: .*python/object/apply"):
        reader(path)
    assert not marker.exists()


def test_a_json_config_cannot_carry_code(tmp_path):
    path = tmp_path / "config.json"
    path.write_text(json.dumps({"method": {"py/reduce": [{"py/function": "builtins.open"}, ["x", "w"]]}}))
    with pytest.raises(InputError, match=f"{path}: method must be the name of a position method"):
        Config.load(path)


def test_a_detection_cache_with_an_object_array_runs_no_code(tmp_path):
    from pedenv.evaluation.real_samples import load_detection_cache

    marker, path = tmp_path / "ran", tmp_path / "cache.npz"
    path.write_bytes(npz_with_payload(marker, "a|keypoints"))
    with pytest.raises(ValueError, match="allow_pickle=False"):
        load_detection_cache(path)
    assert not marker.exists()
