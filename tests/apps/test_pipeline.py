"""The pipelined frame loop: outputs in frame order, errors and Ctrl-C keep every finished frame,
realtime pacing drops the frames that arrive while the model is busy (a fake clock: deterministic)."""

from __future__ import annotations

import os
import sys
import threading
import time

import numpy as np
import pytest

from pedenv.apps.pipeline import BLAS_THREADS, DECODE_AHEAD, PipelineConfig, PipelineStats, decoded_ahead, run_frames
from pedenv.errors import InputError
from pedenv.records import Camera, EgoPose, Frame

CAMERA = Camera.from_fov(64, 48)


def _frames(stamps, fail_at: int | None = None):
    for i, t in enumerate(stamps):
        if i == fail_at:
            raise InputError(f"f{i:02d}.png: frame {i} cannot be read")
        yield Frame(i, float(t), CAMERA, EgoPose.from_xy_yaw(0.0, 0.0, 0.0))


def test_outputs_come_in_frame_order_whatever_each_stage_takes():
    rng = np.random.default_rng(3)
    delays = rng.uniform(0.0, 0.004, size=(2, 40))
    written, finished = [], []

    def step(frame):
        time.sleep(delays[0, frame.index])
        return frame.index

    def write(index):
        time.sleep(delays[1, index])
        written.append((index, threading.current_thread().name))

    stats = run_frames(_frames(np.arange(40) * 0.1), step, write, done=finished.append,
                       config=PipelineConfig(read_ahead=2, write_behind=3))
    assert [i for i, _ in written] == finished == list(range(40))
    assert {name for _, name in written} == {"pedenv-writer"}  # written beside the network, not after it
    assert (stats.taken, stats.written, stats.dropped) == (40, 40, 0) and len(stats.latencies_s) == 40
    summary = stats.to_dict()
    assert summary["frames_per_second"] > 0 and summary["latency_ms"]["p95"] >= summary["latency_ms"]["median"] > 0


def _blas_threads() -> list[int]:
    from threadpoolctl import threadpool_info

    return [pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"]


def test_numpys_blas_runs_one_thread_while_the_frames_run_and_its_own_count_again_after():
    before = _blas_threads()
    assert before, "numpy's BLAS is found (its wheels bundle OpenBLAS)"
    seen = []

    def step(frame):
        seen.append((_blas_threads(), np.linalg.inv(np.eye(3) * (frame.index + 1))[0, 0]))
        return frame.index

    run_frames(_frames(np.arange(3) * 0.1), step, lambda _: None)
    assert [threads for threads, _ in seen] == [[BLAS_THREADS] * len(before)] * 3
    assert [round(x, 6) for _, x in seen] == [1.0, 0.5, round(1 / 3, 6)]
    assert _blas_threads() == before


def test_a_bad_frame_stops_the_run_after_every_frame_before_it_is_written():
    written = []
    stats = PipelineStats()
    with pytest.raises(InputError, match=r"f05\.png: frame 5 cannot be read"):
        run_frames(_frames(np.arange(10) * 0.1, fail_at=5), lambda f: f.index, written.append, stats=stats)
    assert written == [0, 1, 2, 3, 4] and stats.written == 5


def test_frames_decoded_ahead_come_in_order_from_their_own_thread_and_a_bad_one_after_the_rest():
    threads = []

    def frames():
        for frame in _frames(np.arange(8) * 0.1, fail_at=6):
            threads.append(threading.current_thread().name)
            yield frame

    taken = []
    with pytest.raises(InputError, match=r"f06\.png: frame 6 cannot be read"):
        for frame in decoded_ahead(frames()):
            taken.append(frame.index)
    assert taken == [0, 1, 2, 3, 4, 5]
    assert set(threads) == {"pedenv-decoder"}


def test_closing_the_frames_decoded_ahead_stops_their_thread_and_closes_the_source():
    closed, read = threading.Event(), []

    def frames():
        try:
            for frame in _frames(np.arange(100) * 0.1):
                read.append(frame.index)
                yield frame
        finally:
            closed.set()  # a video's capture released

    ahead = decoded_ahead(frames())
    assert next(ahead).index == 0
    ahead.close()
    assert closed.wait(5.0)
    assert not any(t.name == "pedenv-decoder" for t in threading.enumerate())
    assert len(read) <= 2 + DECODE_AHEAD  # the frame taken, those queued, the one waiting to be put


def test_ctrl_c_in_the_network_leaves_every_computed_frame_written():
    written = []

    def step(frame):
        if frame.index == 6:
            raise KeyboardInterrupt
        return frame.index

    def slow_write(index):  # the writer lags behind: frames 0-5 wait in its queue at Ctrl-C
        time.sleep(0.01)
        written.append(index)

    with pytest.raises(KeyboardInterrupt):
        run_frames(_frames(np.arange(30) * 0.1), step, slow_write, config=PipelineConfig(write_behind=8))
    assert written == [0, 1, 2, 3, 4, 5]


def test_a_failing_writer_stops_the_run_with_its_own_error():
    seen = []

    def write(index):
        if index == 3:
            raise InputError("out/overlays/000003.png: cannot write the image")
        seen.append(index)

    with pytest.raises(InputError, match="000003.png: cannot write the image"):
        run_frames(_frames(np.arange(500) * 0.1), lambda f: f.index, write, config=PipelineConfig(write_behind=2))
    assert seen == [0, 1, 2]


class FakeClock:
    """A clock that moves only when slept on or when the fake model works."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.slept = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.slept.append(round(seconds, 9))
        self.now += seconds


@pytest.mark.parametrize("work_s, stamps, processed", [
    # 10 Hz, the model takes 0.25 s: frames 1-2 arrive while it works on 0, 4-5 while on 3 ...
    (0.25, np.arange(10) * 0.1, [0, 3, 6, 9]),
    # the model keeps up: nothing dropped
    (0.05, np.arange(10) * 0.1, list(range(10))),
    # a frame exactly when the model is done is taken; a gap in time is waited out
    (0.2, [0.0, 0.1, 0.2, 5.0, 5.1, 5.3], [0, 2, 3, 5]),
    # time running backwards: those frames arrived "before" the model was free
    (0.05, [0.0, 0.1, 0.05, 0.2], [0, 1, 3]),
])
def test_realtime_drops_the_frames_that_arrive_while_the_model_is_busy(work_s, stamps, processed):
    clock = FakeClock()
    done = []

    def step(frame):
        clock.now += work_s
        return frame.index

    stats = run_frames(_frames(stamps), step, done.append, config=PipelineConfig(realtime=True), clock=clock,
                       sleep=clock.sleep)
    assert done == processed
    assert stats.dropped == len(stamps) - len(processed) and stats.taken == len(processed)
    assert clock.now - 1000.0 == pytest.approx(stamps[processed[-1]] + work_s)


@pytest.mark.parametrize("changes, message", [
    ({"read_ahead": 0}, r"pipeline\.read_ahead must be an integer in \[1, 64\], got 0"),
    ({"read_ahead": 2.5}, r"pipeline\.read_ahead must be an integer"),
    ({"write_behind": True}, r"pipeline\.write_behind must be an integer in \[1, 256\], got True"),
    ({"write_behind": 257}, r"pipeline\.write_behind"),
    ({"realtime": "yes"}, r"pipeline\.realtime must be true or false, got 'yes'"),
    ({"nice": -1}, r"pipeline\.nice must be an integer in \[0, 19\], got -1"),
    ({"nice": 20}, r"pipeline\.nice must be an integer in \[0, 19\], got 20"),
])
def test_pipeline_settings_are_checked(changes, message):
    with pytest.raises(InputError, match=message):
        PipelineConfig(**changes)


def _niceness() -> int:
    return os.getpriority(os.PRIO_PROCESS, threading.get_native_id())


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="a thread's own niceness is Linux's")
@pytest.mark.parametrize("nice", [None, 0, 10, 19])
def test_reading_and_writing_run_nicer_than_the_network(nice):
    seen: dict[str, set[int]] = {"read": set(), "step": set(), "write": set()}

    def frames():
        for frame in _frames(np.arange(5) * 0.1):
            seen["read"].add(_niceness())
            yield frame

    def step(frame):
        seen["step"].add(_niceness())
        return frame.index

    run_frames(frames(), step, lambda _: seen["write"].add(_niceness()), config=PipelineConfig(nice=nice))
    (network,) = seen["step"]
    assert network == _niceness()  # the calling thread keeps its own
    assert seen["read"] == seen["write"] == {min(19, network + (nice or 0))}
