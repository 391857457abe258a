"""The Rerun recordings read back with rerun's own reader: one per scene, frames, pedestrians, entities."""

import functools
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import rerun.dataframe as rrd
from sink_runs import FRAMES, FailingModel

from pedenv.skeleton import COCO_BONES

SCENES = ("red-light-crossing", "drive-30kmh-sidewalk")


@functools.lru_cache(maxsize=8)
def _table(path: Path):
    recording = rrd.load_recording(path)
    return recording, recording.view(index="frame", contents="/**").select().read_all()


def _lines(folder: Path, scene: str) -> list[dict]:
    lines = [json.loads(line) for line in (folder / "environment.jsonl").read_text().splitlines()]
    return [line for line in lines if line["scene"] == scene]


def test_one_recording_per_scene_with_every_frame_and_pedestrian(evaluated):
    folder, result, _ = evaluated
    assert not [w for w in result.extras["warnings"] if "Rerun" in w or "Batch" in w]
    assert sorted(p.name for p in folder.glob("*.rrd")) == sorted(f"run-{s}.rrd" for s in SCENES)
    for scene in SCENES:
        recording, table = _table(folder / f"run-{scene}.rrd")
        assert recording.recording_id() == f"pedenv-{scene}"
        assert table.num_rows == FRAMES
        assert table.column("frame").to_pylist() == list(range(FRAMES))
        lines = _lines(folder, scene)
        labels = table.column("/world/pedestrians/positions:Text").to_pylist()
        assert labels == [[str(p["track_id"]) for p in line["pedestrians"]] for line in lines]
        points = table.column("/world/pedestrians/positions:Position3D").to_pylist()
        assert np.allclose(np.array(points[-1]), [p["position"] for p in lines[-1]["pedestrians"]], atol=1e-3)
        ellipses = table.column("/world/pedestrians/ellipses:LineStrip3D").to_pylist()
        assert [len(e) for e in ellipses] == [len(line["pedestrians"]) for line in lines]
        ids = {p["track_id"] for line in lines for p in line["pedestrians"]}
        entities = {c.split(":")[0] for c in table.column_names}
        assert {f"/world/pedestrians/skeletons/{i}" for i in ids} <= entities
        assert {f"/world/ego/camera/image/skeletons/{i}" for i in ids} <= entities
        for entity in ("/world/ego", "/world/ego_trajectory/0", "/world/pedestrians/velocities",
                       "/world/ground_truth/positions", "/world/ego/camera/image/boxes"):
            assert entity in entities
        trajectory = table.column("/world/ego_trajectory/0:LineStrip3D").to_pylist()
        assert len(trajectory[-1][0]) == FRAMES  # the path so far (one piece: FRAMES < 100), one point per frame


def test_the_camera_is_a_pinhole_and_the_image_is_logged_where_the_frame_has_one(evaluated):
    folder, _, scenes = evaluated
    recording, _ = _table(folder / "run-drive-30kmh-sidewalk.rrd")
    static = recording.view(index="frame", contents="/**").select_static().read_all()
    k = np.array(static.column("/world/ego/camera/image:PinholeProjection").to_pylist()[0]).reshape(3, 3).T
    assert np.allclose(k, scenes[1].frames[0].camera.intrinsics)
    context = static.column("/:AnnotationContext").to_pylist()[0][0][0]["class_description"]
    assert len(context["keypoint_connections"]) == len(COCO_BONES) and len(context["keypoint_annotations"]) == 17
    _, with_image = _table(folder / "run-drive-30kmh-sidewalk.rrd")
    _, without = _table(folder / "run-red-light-crossing.rrd")
    assert "/world/ego/camera/image:Blob" in with_image.column_names
    assert "/world/ego/camera/image:Blob" not in without.column_names


def test_rerun_cli_verifies_the_files(evaluated):
    folder, _, _ = evaluated
    cli = Path(sys.executable).parent / "rerun"
    done = subprocess.run([str(cli), "rrd", "verify", *map(str, sorted(folder.glob("*.rrd")))], capture_output=True,
                          text=True, timeout=120, env={"RERUN_ANALYTICS": "0", "PATH": ""})
    assert done.returncode == 0, done.stderr
    assert "2 files verified without error" in done.stdout + done.stderr


def test_a_run_stopped_by_a_bad_frame_keeps_the_finished_frames(interrupted):
    _, first = _table(interrupted / "run-red-light-crossing.rrd")
    _, second = _table(interrupted / "run-drive-30kmh-sidewalk.rrd")
    assert first.num_rows == FRAMES
    assert second.column("frame").to_pylist() == list(range(FailingModel.FAIL_AT))


def test_a_single_scene_keeps_the_file_name_given(tmp_path):
    from dataclasses import replace

    from sink_runs import short_scenes

    from pedenv.detection import create_detector
    from pedenv.model import PedestrianEnvironmentModel
    from pedenv.outputs.rerun_log import RerunWriter

    scene = short_scenes()[0]
    model, backend = PedestrianEnvironmentModel(), create_detector("detector-model")
    writer = RerunWriter(tmp_path / "one.rrd")
    for frame in scene.frames[:12]:
        frame = replace(frame, detections=backend(frame))
        writer.write(model.update(frame), frame)
    writer.close()
    assert writer.files == [tmp_path / "one.rrd"]
    assert _table(tmp_path / "one.rrd")[1].num_rows == 12
