"""``evaluate_command`` and ``demo_command``: the rules between the flags of ``pedenv evaluate`` and
``pedenv demo``, each refused with one line before the output folder is touched; one real evaluation."""

import hashlib
import shutil
import warnings
from functools import partial
from pathlib import Path

import pytest

from pedenv.apps.demo import demo_command
from pedenv.apps.evaluate_command import DatasetChoice, evaluate_command
from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions
from pedenv.errors import InputError
from pedenv.paths import MARKER
from pedenv.synthetic.storage import write_scenes


@pytest.fixture(scope="module")
def stored(tmp_path_factory, short_scenes):
    """The three short scenes as the ``synthetic`` dataset on disk."""
    root = tmp_path_factory.mktemp("stored")
    write_scenes(short_scenes, root)
    return root


def _evaluate(root, out, *, name="synthetic", scenes=None, **given):
    """evaluate_command with the defaults of ``pedenv evaluate`` but for the groups ``given``."""
    groups = {"flags": OutputFlags(), "pose": PoseOptions(None, detection=None), "method": MethodOptions(),
              "executor": ExecutorOptions(), **given}
    return evaluate_command(dataset=DatasetChoice(name, root, scenes=scenes), output=OutputOptions(out), **groups)


def _literal(message: str) -> str:
    return "^" + message.replace("(", r"\(").replace(")", r"\)")


@pytest.mark.parametrize("given, message", [
    ({"name": "waymo"}, "unknown dataset 'waymo'; valid: synthetic, nuscenes, carla, kitti"),
    ({"method": MethodOptions(refine=False)},
     "--no-refinement and --initial-estimate change the paper's method, not fused; add --method paper"),
    ({"method": MethodOptions(method="fused", initial_estimate="midpoint")},
     "--no-refinement and --initial-estimate change the paper's method, not fused"),
    ({"method": MethodOptions(method="magic")}, "unknown position method 'magic'; valid: paper, fused"),
    ({"pose": PoseOptions(None, detection="fast")},
     "--detection and --device apply to the onnx pose backend; add --pose-backend onnx"),
    ({"pose": PoseOptions("ground-truth", detection=None, device="cpu")},
     "--detection and --device apply to the onnx pose backend"),
    ({"executor": ExecutorOptions(address="10.0.0.1:6379")}, "--address and --workers apply to --executor ray"),
    ({"executor": ExecutorOptions(workers=2)}, "--address and --workers apply to --executor ray"),
    ({"executor": ExecutorOptions("ray"), "method": MethodOptions(method="both")},
     "--method both run in the serial in-process evaluation only; leave out --executor ray and --resume"),
    ({"executor": ExecutorOptions(resume=True), "ablation": True, "flags": OutputFlags(parquet=True,
                                                                                      ros=Path("r.mcap"))},
     "--ablation, --parquet, --ros-out run in the serial in-process evaluation only"),
    ({"executor": ExecutorOptions("dask")}, "unknown executor 'dask'; valid: serial, ray"),
])
def test_flags_that_do_not_go_together_are_refused(stored, tmp_path, given, message):
    with pytest.raises(InputError, match=_literal(message)):
        _evaluate(stored, tmp_path / "out", **given)
    assert not (tmp_path / "out" / "metrics.json").exists()


def test_the_paper_flags_go_with_both_methods():
    """``--method both`` runs the paper's method too, so its ablation flags are taken."""
    cfg = MethodOptions(method="both", refine=False, initial_estimate="midpoint").load(allow_both=True)
    assert (cfg.method, cfg.paper.refine, cfg.paper.initial_estimate) == ("fused", False, "midpoint")
    with pytest.raises(InputError, match="unknown position method 'both'"):
        MethodOptions(method="both").load()  # run and demo take one method


def test_one_scene_is_evaluated_in_this_process(stored, tmp_path):
    outcome = _evaluate(stored, tmp_path / "out", pose=PoseOptions("ground-truth", detection=None),
                        scenes=("red-light-crossing",))
    assert outcome.metrics is not None and outcome.methods == {} and outcome.distributed is None
    assert [name for name, _ in outcome.metrics.scenes] == ["red-light-crossing"]
    overall = outcome.metrics.overall  # measured: 512 matches, 3.42 % (ground-truth skeletons, seed 0)
    assert outcome.metrics.info["method"] == "fused" and overall.count == 512
    assert overall.rel_error_pct == pytest.approx(3.42, abs=0.1)
    assert (tmp_path / "out" / "metrics.json").is_file()


def test_demo_refuses_a_bad_method_before_its_folder_is_made(tmp_path):
    with pytest.raises(InputError, match="unknown position method 'magic'"):
        demo_command(output=OutputOptions(tmp_path / "demo"), flags=OutputFlags(), method=MethodOptions(method="magic"))
    assert not (tmp_path / "demo").exists()


# issue 32: no output on an input; --overwrite removes only what pedenv wrote ---------------------


def _digest(*paths: Path) -> dict[str, str]:
    """sha256 of every file under ``paths``, by path."""
    files = [f for p in paths for f in ([p] if p.is_file() else sorted(p.rglob("*"))) if f.is_file()]
    return {str(f): hashlib.sha256(f.read_bytes()).hexdigest() for f in files}


def _copy(stored, tmp_path) -> Path:
    root = tmp_path / "data"
    shutil.copytree(stored, root)
    return root


@pytest.mark.parametrize("where, message", [
    ("output", r"^--output .*data/out lies inside the input --data-root"),
    ("mcap", r"^--mcap .*data/x\.mcap lies inside the input --data-root"),
    ("rerun", r"^--rerun .*red-light-crossing/x\.rrd lies inside the input --data-root"),
])
def test_evaluate_refuses_an_output_inside_the_data_root(stored, tmp_path, where, message):
    root = _copy(stored, tmp_path)
    before = _digest(root)
    out, flags = tmp_path / "out", OutputFlags()
    if where == "output":
        out = root / "out"
    elif where == "mcap":
        flags = OutputFlags(mcap=root / "x.mcap")
    else:
        flags = OutputFlags(rerun=root / "red-light-crossing" / "x.rrd")
    with pytest.raises(InputError, match=message):
        _evaluate(root, out, flags=flags, pose=PoseOptions("ground-truth", detection=None))
    assert _digest(root) == before and not (tmp_path / "out").exists()


def test_evaluate_overwrite_refuses_a_folder_holding_the_data_or_the_config(stored, tmp_path):
    out = tmp_path / "out"
    _evaluate(stored, out, pose=PoseOptions("ground-truth", detection=None), scenes=("red-light-crossing",))
    shutil.copytree(stored, out / "data")  # the dataset moved into the earlier evaluation's folder
    config = out / "config.json"
    before = _digest(out)
    for root, method, flag in [(out / "data", MethodOptions(), "--data-root"),
                               (stored, MethodOptions(config=config), "--config")]:
        with pytest.raises(InputError, match=rf"^--output {out} holds the input {flag}"):
            evaluate_command(dataset=DatasetChoice("synthetic", root, scenes=("red-light-crossing",)),
                             output=OutputOptions(out, overwrite=True), flags=OutputFlags(),
                             pose=PoseOptions("ground-truth", detection=None), method=method,
                             executor=ExecutorOptions())
        assert _digest(out) == before


def test_evaluate_overwrite_replaces_its_own_files_only(stored, tmp_path):
    """The marker lists what the evaluation wrote: a file of the user's added there is refused by name."""
    out = tmp_path / "out"
    run = partial(evaluate_command, dataset=DatasetChoice("synthetic", stored, scenes=("red-light-crossing",)),
                  output=OutputOptions(out, overwrite=True), flags=OutputFlags(),
                  pose=PoseOptions("ground-truth", detection=None), method=MethodOptions(), executor=ExecutorOptions())
    run()
    assert "metrics.json" in (out / MARKER).read_text().splitlines()
    run()  # its own files: replaced
    (out / "notes.txt").write_text("mine")
    before = _digest(out)
    with pytest.raises(InputError, match=r"notes\.txt, which pedenv did not write"):
        run()
    assert _digest(out) == before


def test_demo_refuses_its_config_inside_the_output_folder(tmp_path):
    out = tmp_path / "demo"
    out.mkdir()
    (out / MARKER).write_text("written by pedenv demo; --overwrite may delete this folder's contents\n")
    (out / "config.json").write_text("{}\n")
    before = _digest(out)
    with pytest.raises(InputError, match=rf"^--output {out} holds the input --config {out / 'config.json'}"):
        demo_command(output=OutputOptions(out, overwrite=True), flags=OutputFlags(),
                     method=MethodOptions(config=out / "config.json"))
    assert _digest(out) == before


def test_demo_refuses_an_output_on_its_config(tmp_path):
    config = tmp_path / "c.mcap"  # a config of any name; the output must not be it
    config.write_text("{}\n")
    with pytest.raises(InputError, match=r"^--mcap .*c\.mcap is the input --config"):
        demo_command(output=OutputOptions(tmp_path / "demo", overwrite=True), flags=OutputFlags(mcap=config),
                     method=MethodOptions(config=config))
    assert config.read_text() == "{}\n" and not (tmp_path / "demo").exists()


def test_evaluate_refuses_an_output_hard_linked_to_a_dataset_file(stored, tmp_path):
    root = _copy(stored, tmp_path)
    data_file = next(p for p in sorted(root.rglob("*")) if p.is_file())
    link = tmp_path / "x.mcap"
    link.hardlink_to(data_file)
    before = _digest(root)
    with pytest.raises(InputError, match=rf"^--mcap {link} is the input --data-root {data_file}"):
        evaluate_command(dataset=DatasetChoice("synthetic", root),
                         output=OutputOptions(tmp_path / "out", overwrite=True), flags=OutputFlags(mcap=link),
                         pose=PoseOptions("ground-truth", detection=None), method=MethodOptions(),
                         executor=ExecutorOptions())
    assert _digest(root) == before


def test_evaluate_overwrite_keeps_earlier_files_outside_the_folder_when_it_stops(stored, tmp_path):
    """``--rerun`` (one file per scene) outside the output folder: an evaluation that stops at
    a damaged scene leaves the earlier files byte for byte, the new ones beside them named in warnings;
    one that finishes renames them over the earlier ones."""
    root = _copy(stored, tmp_path)
    side = tmp_path / "side"
    flags = OutputFlags(rerun=side / "r.rrd")
    first, *_, last = sorted(p.name for p in root.iterdir() if p.is_dir())

    def evaluate(out):
        return evaluate_command(dataset=DatasetChoice("synthetic", root, scenes=(first, last)),
                                output=OutputOptions(out, overwrite=True), flags=flags,
                                pose=PoseOptions("ground-truth", detection=None), method=MethodOptions(),
                                executor=ExecutorOptions())

    evaluate(tmp_path / "o1")
    before = _digest(side)
    assert len(before) == 2  # r-<scene>.rrd for each of the 2 scenes
    damaged = root / last / "frames.npz"
    good = damaged.read_bytes()
    damaged.write_bytes(good[:100])
    with warnings.catch_warnings(record=True) as caught, pytest.raises(InputError, match="frames.npz"):
        warnings.simplefilter("always")
        evaluate(tmp_path / "o2")
    assert _digest(side).items() >= before.items()
    beside = [p for p in side.iterdir() if p.name.startswith(".pedenv-new-")]
    kept = [str(w.message) for w in caught if "is kept as it was" in str(w.message)]
    assert len(beside) == len(kept) >= 1  # one file (a recording split into scenes when it closes whole)
    for path in beside:
        path.unlink()
    damaged.write_bytes(good)
    inodes = {p.name: p.stat().st_ino for p in side.iterdir()}
    evaluate(tmp_path / "o3")
    assert sorted(p.name for p in side.iterdir()) == sorted(inodes)  # renamed over, nothing beside
    assert all(p.stat().st_ino != inodes[p.name] for p in side.iterdir())
