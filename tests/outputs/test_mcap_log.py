"""The MCAP file read back with the mcap reader: topics, message counts, decoded content."""

import functools
import json
from pathlib import Path

import numpy as np
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader
from sink_runs import FRAMES, FailingModel

TOPICS = {"/tf": "foxglove.FrameTransforms", "/pedestrians": "foxglove.SceneUpdate",
          "/ground_truth": "foxglove.SceneUpdate", "/ego": "foxglove.SceneUpdate",
          "/camera/calibration": "foxglove.CameraCalibration", "/camera/image": "foxglove.CompressedImage",
          "/camera/annotations": "foxglove.ImageAnnotations"}


@functools.cache
def _message_class(name: str, schema_data: bytes):
    pool = descriptor_pool.DescriptorPool()
    for proto in descriptor_pb2.FileDescriptorSet.FromString(schema_data).file:
        pool.Add(proto)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(name))


def _messages(path: Path, topic: str) -> list:
    """(log_time ns, decoded message) of ``topic``: protobuf messages decoded with their own schema, JSON parsed."""
    out = []
    with path.open("rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(topics=[topic]):
            if channel.message_encoding == "json":
                out.append((message.log_time, json.loads(message.data)))
            else:
                out.append((message.log_time, _message_class(schema.name, schema.data).FromString(message.data)))
    return out


def test_topics_schemas_and_message_counts(evaluated):
    folder, _, _ = evaluated
    with (folder / "run.mcap").open("rb") as f:
        summary = make_reader(f).get_summary()
    counts = summary.statistics.channel_message_counts
    found = {c.topic: (summary.schemas[c.schema_id].name if c.schema_id else "", counts[i])
             for i, c in summary.channels.items()}
    for topic, schema in TOPICS.items():
        frames = FRAMES if topic == "/camera/image" else 2 * FRAMES  # only the second scene has an image
        assert found[topic] == (schema, frames), topic
    assert found["/environment"][1] == 2 * FRAMES


def test_pedestrians_match_the_environment_model(evaluated):
    folder, _, _ = evaluated
    lines = [json.loads(line) for line in (folder / "environment.jsonl").read_text().splitlines()]
    updates = _messages(folder / "run.mcap", "/pedestrians")
    environment = _messages(folder / "run.mcap", "/environment")
    times = [t for t, _ in updates]
    assert times == sorted(times) and len(set(times)) == len(times)  # the second scene plays after the first
    for (_, update), (_, record), line in zip(updates, environment, lines):
        assert record["frame"] == line["frame"] and record["scene"] == line["scene"]
        assert [e.id for e in update.entities] == [f"ped-{p['track_id']}" for p in line["pedestrians"]]
        assert len(update.deletions) == 1
        for entity, ped in zip(update.entities, line["pedestrians"]):
            centre = entity.spheres[0].pose.position
            assert np.allclose([centre.x, centre.y, centre.z - 0.2], ped["position"], atol=1e-3)
            assert entity.texts[0].text == str(ped["track_id"])
            assert len(entity.lines[0].points) % 2 == 0
            # skeleton, ellipse; with behaviour the predicted path and one ellipse per horizon
            beh = ped.get("behaviour")
            assert len(entity.lines) == 2 + (1 + len(beh["predicted_positions"]) if beh else 0)
            if beh:
                path = entity.lines[2].points
                assert np.allclose([path[-1].x, path[-1].y], beh["predicted_positions"][-1], atol=1e-3)
                assert len(entity.arrows) == (ped["velocity"] != [0, 0, 0]) + (beh["orientation_availability"]
                                                                              != "unavailable")


def test_transforms_image_and_annotations(evaluated):
    folder, _, scenes = evaluated
    tf = _messages(folder / "run.mcap", "/tf")
    first = scenes[0].frames[0]
    world_ego, ego_camera = tf[0][1].transforms
    assert (world_ego.parent_frame_id, world_ego.child_frame_id) == ("world", "ego")
    assert (ego_camera.parent_frame_id, ego_camera.child_frame_id) == ("ego", "camera")
    t = world_ego.translation
    assert np.allclose([t.x, t.y, t.z], first.ego.translation)
    images = _messages(folder / "run.mcap", "/camera/image")
    assert images[0][1].format == "jpeg" and images[0][1].data[:2] == b"\xff\xd8"
    annotations = _messages(folder / "run.mcap", "/camera/annotations")
    lines = [json.loads(line) for line in (folder / "environment.jsonl").read_text().splitlines()]
    assert [len(a.texts) for _, a in annotations] == [len(line["pedestrians"]) for line in lines]
    calibration = _messages(folder / "run.mcap", "/camera/calibration")[0][1]
    assert np.allclose(np.array(calibration.K).reshape(3, 3), first.camera.intrinsics)


def test_a_run_stopped_by_a_bad_frame_leaves_a_readable_file(interrupted):
    updates = _messages(interrupted / "run.mcap", "/environment")
    assert len(updates) == FRAMES + FailingModel.FAIL_AT
    assert updates[-1][1]["frame"] == FailingModel.FAIL_AT - 1
