"""``evaluate_command`` and ``demo_command``: the rules between the flags of ``pedenv evaluate`` and
``pedenv demo``, each refused with one line before the output folder is touched; one real evaluation."""

from pathlib import Path

import pytest

from pedenv.apps.demo import demo_command
from pedenv.apps.evaluate_command import DatasetChoice, evaluate_command
from pedenv.apps.options import ExecutorOptions, MethodOptions, OutputFlags, OutputOptions, PoseOptions
from pedenv.errors import InputError
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
    overall = outcome.metrics.overall  # measured: 512 matches, 3.67 % (ground-truth skeletons, seed 0)
    assert outcome.metrics.info["method"] == "fused" and overall.count == 512
    assert overall.rel_error_pct == pytest.approx(3.67, abs=0.1)
    assert (tmp_path / "out" / "metrics.json").is_file()


def test_demo_refuses_a_bad_method_before_its_folder_is_made(tmp_path):
    with pytest.raises(InputError, match="unknown position method 'magic'"):
        demo_command(output=OutputOptions(tmp_path / "demo"), flags=OutputFlags(), method=MethodOptions(method="magic"))
    assert not (tmp_path / "demo").exists()
