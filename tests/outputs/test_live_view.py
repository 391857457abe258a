"""``--live``: a WebSocket client on 127.0.0.1 sees the pedestrians of each frame as the model writes it."""

import asyncio
import base64
import json
import struct
from dataclasses import replace

import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from sink_runs import short_scenes

from pedenv.config import Config
from pedenv.detection import create_detector
from pedenv.errors import InputError
from pedenv.model import PedestrianEnvironmentModel

websockets = pytest.importorskip("websockets", reason="the test extra")
FRAMES = 8


def _states():
    """(state, frame) of the first frames of a built-in scene, with the ground-truth skeletons."""
    scene = short_scenes()[0]
    model, pose = PedestrianEnvironmentModel(Config()), create_detector("ground-truth")
    out = []
    for frame in scene.frames[:FRAMES]:
        frame = replace(frame, detections=pose(frame))
        out.append((model.update(frame), frame))
    return out


def _decoder(channel: dict):
    pool = descriptor_pool.DescriptorPool()
    for proto in descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"])).file:
        pool.Add(proto)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


async def _watch(port: int, write) -> list:
    """Connect, subscribe to /pedestrians, let ``write`` run in a thread, collect the decoded updates."""
    async with websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"],
                                  max_size=None) as ws:
        channels: dict = {}
        while "/pedestrians" not in channels:
            msg = json.loads(await asyncio.wait_for(ws.recv(), 10))
            if msg["op"] == "advertise":
                channels.update({c["topic"]: c for c in msg["channels"]})
        channel = channels["/pedestrians"]
        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7, "channelId": channel["id"]}]}))
        await asyncio.sleep(0.5)  # the server takes the subscription before the run writes
        writing = asyncio.get_running_loop().run_in_executor(None, write)
        decode, updates = _decoder(channel), []
        while len(updates) < FRAMES:
            data = await asyncio.wait_for(ws.recv(), 10)
            if isinstance(data, bytes) and data[0] == 1:  # message data: op, subscription, log time, payload
                subscription, _ = struct.unpack_from("<IQ", data, 1)
                assert subscription == 7
                updates.append(decode.FromString(data[13:]))
        await writing
        return updates


def test_a_viewer_sees_every_pedestrian_of_every_frame_as_it_is_written():
    from pedenv.outputs.live_view import LiveViewer

    states = _states()
    viewer = LiveViewer(port=0)
    try:
        assert viewer.port > 0
        updates = asyncio.run(_watch(viewer.port, lambda: [viewer.write(s, f) for s, f in states]))
    finally:
        viewer.close()
    seen = 0
    for update, (state, _) in zip(updates, states, strict=True):
        ids = [e.id for e in update.entities]
        assert ids == [f"ped-{int(i)}" for i in state.pedestrians.track_ids]
        for entity, position in zip(update.entities, state.pedestrians.positions):
            assert entity.spheres[0].pose.position.x == pytest.approx(position[0])
        seen += len(ids)
    assert seen >= FRAMES  # people in view


def test_a_port_outside_the_range_is_refused():
    from pedenv.outputs.live_view import LiveViewer

    with pytest.raises(InputError, match=r"--live port must be in \[0, 65535\], got 70000"):
        LiveViewer(port=70000)
