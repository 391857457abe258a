"""``--ros-out``: the ROS 2 bag read back with rosbags and with mcap-ros2-support, field by field
against environment.jsonl (two short built-in scenes; a run stopped by a bad frame)."""

import uuid

import numpy as np
import pytest
from sink_runs import FailingModel, short_scenes

from pedenv.apps.evaluate import run_evaluation
from pedenv.config import Config
from pedenv.datasets.memory import MemoryDataset
from pedenv.errors import InputError
from pedenv.outputs.jsonl import read_environment
from pedenv.outputs.ros_bag import TOPICS
from pedenv.outputs.ros_messages import UUID_NAMESPACE
from pedenv.outputs.sinks import ExtraOutputs
from pedenv.records import Scene

FRAMES = 12  # per scene


class _FailingEarly(FailingModel):
    FAIL_AT = 7

pytest.importorskip("rosbags", reason="the ros extra")
pytest.importorskip("mcap_ros2", reason="the ros extra")


def _run(folder, model_factory=None):
    scenes = [Scene(s.name, s.frames[:FRAMES]) for s in short_scenes()]
    dataset = MemoryDataset(scenes, name="synthetic", default_pose_backend="detector-model")
    options = {"model_factory": model_factory} if model_factory else {}
    run_evaluation(dataset, config=Config(), output_dir=folder, extra_outputs=ExtraOutputs(ros=folder / "ros.mcap"),
                   **options)
    return folder


@pytest.fixture(scope="module")
def ros_run(tmp_path_factory):
    return _run(tmp_path_factory.mktemp("ros"))


def _with_rosbags(path):
    from pedenv.recordings.bag_source import BagSource

    with BagSource(path) as bag:
        assert {t.name: t.msgtype for t in bag.topics.values()} == TOPICS
        return {topic: [(m.log_ns, m.msg) for m in bag.messages([topic])] for topic in TOPICS}


def _with_mcap_ros2(path):
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict = {topic: [] for topic in TOPICS}
    with open(path, "rb") as f:
        for schema, channel, message, decoded in make_reader(f, decoder_factories=[DecoderFactory()]) \
                .iter_decoded_messages():
            assert schema.name == TOPICS[channel.topic] and schema.encoding == "ros2msg"
            out[channel.topic].append((message.log_time, decoded))
    return out


def _ns(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _check(messages, lines) -> None:
    """Every message against its environment.jsonl line (3 decimals, as the JSON Lines)."""
    assert all(len(messages[t]) == len(lines) for t in TOPICS)
    r = lambda a: np.round(np.asarray(a, float), 3)  # noqa: E731
    for k, line in enumerate(lines):
        log_ns, det = messages["/pedestrians"][k]
        peds = line["pedestrians"]
        assert _ns(det.header.stamp) == log_ns and det.header.frame_id == "world"
        assert [d.id for d in det.detections] == [str(p["track_id"]) for p in peds]
        for d, p in zip(det.detections, peds):
            (hyp,) = d.results
            assert hyp.hypothesis.class_id == "pedestrian" and _ns(d.header.stamp) == log_ns
            pos = hyp.pose.pose.position
            assert r([pos.x, pos.y, pos.z]).tolist() == p["position"]
            cov = np.asarray(hyp.pose.covariance).reshape(6, 6)
            assert r(cov[:2, :2]).tolist() == p["covariance_xy"]
            assert d.bbox.size.x == 0.6 and 1.0 <= d.bbox.size.z <= 2.2
            assert d.bbox.center.position.z == pytest.approx(pos.z + d.bbox.size.z / 2)
        _, tracked = messages["/pedestrians/tracked_objects"][k]
        for o, p in zip(tracked.objects, peds, strict=True):
            assert bytes(o.object_id.uuid) == uuid.uuid5(UUID_NAMESPACE, f"{line['scene']}/{p['track_id']}").bytes
            assert [(c.label, c.probability) for c in o.classification] == [(7, 1.0)]
            kin = o.kinematics
            v = kin.twist_with_covariance.twist.linear
            assert r([v.x, v.y, v.z]).tolist() == p["velocity"]
            q = kin.pose_with_covariance.pose.position
            assert r([q.x, q.y]).tolist() == p["position"][:2]
            assert r(np.asarray(kin.pose_with_covariance.covariance).reshape(6, 6)[:2, :2]).tolist() == \
                p["covariance_xy"]
            assert kin.orientation_availability == 0 and o.shape.type == 1
        _, tf = messages["/tf"][k]
        ego = tf.transforms[0]
        assert (ego.header.frame_id, ego.child_frame_id) == ("world", "base_link")
        t = ego.transform.translation
        assert r([t.x, t.y, t.z]).tolist() == line["ego"]["translation"]
        assert tf.transforms[1].child_frame_id == "camera_optical"
        _, markers = messages["/pedestrians/markers"][k]
        assert markers.markers[0].action == 3 and len(markers.markers) == 1 + 4 * len(peds)
        ids = [m.text for m in markers.markers if m.type == 9]
        assert ids == [str(p["track_id"]) for p in peds]


def test_both_readers_find_every_pedestrian_of_the_environment_model(ros_run):
    lines = read_environment(ros_run / "environment.jsonl")
    assert len(lines) == 2 * FRAMES and sum(len(line["pedestrians"]) for line in lines) > 30
    for read in (_with_rosbags, _with_mcap_ros2):
        messages = read(ros_run / "ros.mcap")
        _check(messages, lines)
        stamps = [ns for ns, _ in messages["/pedestrians"]]
        assert np.all(np.diff(stamps) > 0)  # the second scene shifted after the first
    assert not (ros_run / "ros.mcap.partial").exists()


def test_a_run_stopped_by_a_bad_frame_keeps_the_frames_before_it(tmp_path):
    with pytest.raises(InputError, match="broken on purpose"):
        _run(tmp_path, _FailingEarly)
    lines = read_environment(tmp_path / "environment.jsonl")
    assert len(lines) == FRAMES + _FailingEarly.FAIL_AT
    for read in (_with_rosbags, _with_mcap_ros2):
        _check(read(tmp_path / "ros.mcap"), lines)
