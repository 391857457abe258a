"""Scenes as tasks: the same metrics.json and environment.jsonl as the serial run, failures per scene, --resume."""

import json

import numpy as np
import pytest

from pedenv.apps.distributed import SCENES_FOLDER, evaluate_distributed, evaluate_on
from pedenv.apps.evaluate import evaluate_dataset
from pedenv.apps.evaluation_outputs import write_outputs
from pedenv.apps.executors import RayExecutor, SerialExecutor
from pedenv.apps.options import ExecutorOptions
from pedenv.config import Config
from pedenv.errors import InputError
from pedenv.synthetic.dataset import SyntheticDataset
from pedenv.synthetic.storage import write_scenes

SERIAL, RESUME = ExecutorOptions("serial"), ExecutorOptions("serial", resume=True)


def _without_timings(folder):
    """metrics.json but the stage timings: wall times, never equal between two runs."""
    metrics = json.loads((folder / "metrics.json").read_text())
    assert metrics.pop("timing_ms")["tracking_per_frame"] > 0
    return metrics


def _stored(scenes, root):
    """The scenes written as the ``synthetic`` dataset on disk, and that dataset."""
    write_scenes(scenes, root)
    return SyntheticDataset(root)


def _assert_same_outputs(serial, other):
    assert _without_timings(serial) == _without_timings(other)
    assert (serial / "environment.jsonl").read_bytes() == (other / "environment.jsonl").read_bytes()


def test_serial_executor_gives_the_serial_runs_outputs(short_dataset, tmp_path):
    evaluate_dataset(short_dataset, output_dir=tmp_path / "serial")
    result = evaluate_distributed(short_dataset, executor=SERIAL, output_dir=tmp_path / "tasks")
    _assert_same_outputs(tmp_path / "serial", tmp_path / "tasks")
    assert result.metrics.overall.count > 500 and len(result.metrics.scenes) == 3
    assert sorted(p.name for p in (tmp_path / "tasks" / SCENES_FOLDER).iterdir()) == sorted(short_dataset.scene_names())


@pytest.mark.ray
def test_ray_gives_the_serial_runs_metrics_and_environment(ray_session, short_dataset, tmp_path):
    evaluate_dataset(short_dataset, output_dir=tmp_path / "serial")
    with RayExecutor(workers=2) as ex:
        result = evaluate_on(short_dataset, executor=ex, output_dir=tmp_path / "ray", progress=False)
    write_outputs(result, tmp_path / "ray", Config())
    _assert_same_outputs(tmp_path / "serial", tmp_path / "ray")
    assert result.extras["failures"] == {} and result.busiest is not None


@pytest.mark.parametrize("executor", ["serial", pytest.param("ray", marks=pytest.mark.ray)])
def test_a_bad_scene_is_named_and_the_others_finish_then_resume_runs_it(request, executor, short_scenes, tmp_path):
    if executor == "ray":
        request.getfixturevalue("ray_session")
    data = _stored(short_scenes, tmp_path / "data")
    names = data.scene_names()  # sorted
    frames_file = tmp_path / "data" / names[1] / "frames.npz"
    good = frames_file.read_bytes()
    frames_file.write_bytes(good[: len(good) // 2])  # a truncated file: bad data in one scene
    result = evaluate_distributed(data, executor=ExecutorOptions(executor), output_dir=tmp_path / "run")
    assert list(result.extras["failures"]) == [names[1]]
    error = result.extras["failures"][names[1]]
    assert isinstance(error, InputError) and str(frames_file) in str(error)
    metrics = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert [s["name"] for s in metrics["scenes"]] == [names[0], names[2]]
    assert str(frames_file) in metrics["info"]["failed_scenes"][names[1]]
    # the data fixed, --resume runs only the failed scene and gives the full run's outputs
    frames_file.write_bytes(good)
    fixed = SyntheticDataset(tmp_path / "data")
    resumed = evaluate_distributed(fixed, executor=ExecutorOptions(executor, resume=True), output_dir=tmp_path / "run")
    assert resumed.extras["resumed"] == [names[0], names[2]]
    assert resumed.extras["failures"] == {}
    evaluate_dataset(fixed, output_dir=tmp_path / "serial")
    _assert_same_outputs(tmp_path / "serial", tmp_path / "run")


def test_resume_refuses_a_folder_pedenv_did_not_write(short_dataset, tmp_path):
    (tmp_path / "mine.txt").write_text("a user's file\n")
    with pytest.raises(InputError, match="not written by pedenv"):
        evaluate_distributed(short_dataset, executor=RESUME, output_dir=tmp_path)
    assert (tmp_path / "mine.txt").read_text() == "a user's file\n"


def test_a_damaged_checkpoint_is_one_clear_error(short_dataset, tmp_path):
    evaluate_distributed(short_dataset, executor=SERIAL, output_dir=tmp_path / "run")
    name = short_dataset.scene_names()[0]
    checkpoint = tmp_path / "run" / SCENES_FOLDER / name / "result.npz"
    checkpoint.write_bytes(b"not a checkpoint")
    with pytest.raises(InputError, match=f"{checkpoint}: not a pedenv scene checkpoint .*to run scene {name} again"):
        evaluate_distributed(short_dataset, executor=RESUME, output_dir=tmp_path / "run")


def test_serial_executor_reuses_one_pose_backend(short_dataset, tmp_path):
    made = []

    def factory():
        from pedenv.synthetic.detector import DetectorModel

        made.append(1)
        return DetectorModel(0)

    with SerialExecutor() as ex:
        result = evaluate_on(short_dataset, executor=ex, pose_backend=factory)
    assert len(made) == 2  # once to check and name it, once for the (one) worker: not once per scene
    assert result.metrics.info["pose_backend"] == "detector-model"


def test_resume_refuses_a_scene_checkpointed_with_another_method(short_dataset, tmp_path):
    """Issue 19: a scene checkpointed with --method paper was merged into a fused run without a word."""
    name = short_dataset.scene_names()[0]
    evaluate_distributed(short_dataset, executor=SERIAL, scenes=[name], config=Config(method="paper"),
                         output_dir=tmp_path / "run")
    checkpoint = tmp_path / "run" / SCENES_FOLDER / name / "result.npz"
    with pytest.raises(InputError, match=f"{checkpoint}: scene {name} was checkpointed by another run "
                                         r'\(config.method "paper" \(this run: "fused"\), .*delete '):
        evaluate_distributed(short_dataset, executor=RESUME, scenes=[name], output_dir=tmp_path / "run")
    # the same settings resume it
    again = evaluate_distributed(short_dataset, executor=RESUME, scenes=[name], config=Config(method="paper"),
                                 output_dir=tmp_path / "run")
    assert again.extras["resumed"] == [name] and again.metrics.info["method"] == "paper"


def test_ctrl_c_while_a_checkpoint_is_written_leaves_no_checkpoint_and_prints_nothing(short_dataset, tmp_path,
                                                                                     monkeypatch):
    """numpy's savez leaves its ZipFile open when interrupted; written straight into the temporary file, the
    ZipFile later closed itself on the closed file and printed a traceback at exit (seen in a CI run's Ctrl-C)."""
    import gc
    import sys

    from numpy.lib import format as npy_format

    from pedenv.apps.scene_checkpoint import load_checkpoint, save_checkpoint

    evaluate_distributed(short_dataset, executor=SERIAL, output_dir=tmp_path / "run")
    name = short_dataset.scene_names()[0]
    checkpoint = tmp_path / "run" / SCENES_FOLDER / name / "result.npz"
    with np.load(checkpoint) as npz:
        run = json.loads(str(npz["meta"]))["run"]
    result = load_checkpoint(checkpoint, name, run)
    write_array, calls = npy_format.write_array, []

    def interrupted(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return write_array(*args, **kwargs)

    unraisable = []
    monkeypatch.setattr(sys, "unraisablehook", unraisable.append)
    monkeypatch.setattr(npy_format, "write_array", interrupted)
    target = tmp_path / "again.npz"
    with pytest.raises(KeyboardInterrupt):
        save_checkpoint(target, result, run)
    gc.collect()
    assert len(calls) == 3 and unraisable == [] and not target.exists()
