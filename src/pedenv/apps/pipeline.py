"""The pipelined frame loop of ``pedenv run``: read ahead, the network, write behind.

Three stages joined by bounded queues, so that reading and decoding the next frames and
writing the outputs of the last ones overlap the network (onnxruntime and OpenCV release the
GIL while they work):

- a reader thread pulls frames from an iterator (reading and decoding happen there) into a
  queue of ``read_ahead`` frames; where the iterator does more than decode (the visual odometry
  estimating each frame's ego pose), :func:`decoded_ahead` moves the decoding into a thread of its
  own ahead of it, so that on a machine with cores to spare the two overlap;
- the calling thread runs ``step(frame)`` (the network and the model, which must see the
  frames one after the other) on each frame in order;
- a writer thread calls ``write(result)`` on each result in frame order (at most
  ``write_behind`` results wait), then ``done(result)``.

An error in the reader (a bad frame) is raised in the calling thread when the frames before it
are done; an error in the writer stops the run at the next frame and is raised as it is. On
any stop (an error, Ctrl-C) every result already computed is still written before
:func:`run_frames` raises, so every finished frame is on disk.

With ``realtime`` the frames are taken at the recording's own rate: frame ``i`` arrives
``timestamp_i - timestamp_0`` seconds after the first one, and a frame that arrives while
``step`` is still busy with an earlier one is dropped and counted, as a live camera's would be
(no frame is kept waiting). Latency runs from the moment a frame is taken (its arrival with
``realtime``) to the moment ``write`` returned for it.
"""

from __future__ import annotations

import enum
import os
import queue
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any, Final

import numpy as np
from threadpoolctl import threadpool_limits

from pedenv.errors import InputError
from pedenv.records import Frame


class _End(enum.Enum):
    """The end of a queue's items (an enum member: ``item is _END`` narrows an item's type)."""

    END = "end"


_END: Final = _End.END
_POLL_S = 0.1  # how often a blocked stage looks whether the others have stopped
#: BLAS threads while the frames run (numpy's OpenBLAS, or MKL; :func:`run_frames`). pedenv's linear algebra
#: is on small matrices (3x3 intrinsics and rotations, the Kalman filters' few states, a road fit's few hundred
#: points), which one thread does fastest; a BLAS pool only costs there: OpenBLAS's workers busy-wait after
#: each call, so the 3x3 inverses of each frame's visual odometry kept one spinning a whole core beside the
#: network. On 2 cores, KITTI raw 0002 through ``pedenv run`` (``benchmarks/visual_odometry.py --only cost``,
#: medians of 5-6 runs each): with OpenBLAS's pool of 2 the odometry took the process's CPU +37 % and the
#: time +17 % a frame; with one thread +16 % and +9 %.
BLAS_THREADS = 1


@dataclass(frozen=True)
class PipelineConfig:
    """How ``pedenv run`` overlaps reading, the network and writing.

    read_ahead: decoded frames waiting for the network (1..64; 4). More smooths out slow
        reads; each frame holds its image in memory (4.3 MB at 1600x900).
    write_behind: finished frames waiting for their outputs (1..256; 8). More lets the network
        run on while a slow writer (PNG encoding) catches up; each holds its image too.
    realtime: take frames at the recording's own rate and drop those that arrive while the
        model is busy (module doc); False runs every frame as fast as it can.
    nice: how much lower the reader and writer threads run than the network (0..19, added to
        the process's niceness; Linux only, elsewhere ignored). Higher lets the network's threads
        go first and the reading and writing fill the time they leave, which pays while the
        writer needs less time than the network; a writer slower than the network must not wait
        for it (0). None (the default): 0 here, and ``pedenv run`` chooses by its outputs
        (:func:`pedenv.apps.run.run_recording`; docs/speed.md).
    """

    read_ahead: int = 4
    write_behind: int = 8
    realtime: bool = False
    nice: int | None = None

    def __post_init__(self) -> None:
        for name, low, top in (("read_ahead", 1, 64), ("write_behind", 1, 256), ("nice", 0, 19)):
            value = getattr(self, name)
            if name == "nice" and value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= top:
                raise InputError(f"pipeline.{name} must be an integer in [{low}, {top}], got {value!r}")
        if not isinstance(self.realtime, bool):
            raise InputError(f"pipeline.realtime must be true or false, got {self.realtime!r}")


@dataclass
class PipelineStats:
    """What a pipelined run did: frames taken, dropped (``realtime``) and written, the wall
    time from the first frame taken to the last written (s), each written frame's latency (s)."""

    taken: int = 0
    dropped: int = 0
    written: int = 0
    wall_s: float = 0.0
    latencies_s: list[float] = field(default_factory=list)

    def to_dict(self) -> dict:
        """``frames_per_second`` (written frames over the wall time), ``latency_ms`` median and
        95th percentile, ``frames_dropped``, ``wall_s``."""
        lat = np.asarray(self.latencies_s) * 1e3
        return {"frames_per_second": self.written / self.wall_s if self.wall_s > 0 else None,
                "latency_ms": {"median": float(np.median(lat)) if len(lat) else None,
                               "p95": float(np.percentile(lat, 95)) if len(lat) else None},
                "frames_dropped": self.dropped, "wall_s": self.wall_s}


class _Failure:
    """An exception of a stage, passed on in its queue."""

    def __init__(self, exc: BaseException) -> None:
        self.exc = exc


def _put(q: queue.Queue, item: object, stop: threading.Event) -> bool:
    """Put ``item`` unless ``stop`` is set first; whether it was put."""
    while not stop.is_set():
        try:
            q.put(item, timeout=_POLL_S)
            return True
        except queue.Full:
            continue
    return False


def lower_priority(nice: int | None) -> None:
    """Run the calling thread ``nice`` steps nicer than it runs now (Linux: a thread's niceness is
    its own; elsewhere nothing is done). A niceness that cannot be set is left as it is."""
    if not nice or not sys.platform.startswith("linux"):
        return
    tid = threading.get_native_id()
    try:
        os.setpriority(os.PRIO_PROCESS, tid, min(19, os.getpriority(os.PRIO_PROCESS, tid) + nice))
    except OSError:
        return  # a speed hint only: the thread runs on at its niceness


def _read(frames: Iterable[Frame], out: queue.Queue[Frame | _Failure | _End], stop: threading.Event,
          nice: int | None = None) -> None:
    lower_priority(nice)
    iterator = iter(frames)
    try:
        for frame in iterator:
            if not _put(out, frame, stop):
                return
        _put(out, _END, stop)
    except BaseException as exc:  # noqa: BLE001 - handed to the calling thread, raised there
        _put(out, _Failure(exc), stop)
    finally:
        close = getattr(iterator, "close", None)
        if close is not None:
            close()  # a video's capture is released here, in this thread


#: Frames the decoding thread of :func:`decoded_ahead` may run ahead of the stage it feeds: two keep the
#: next frame decoded while the odometry works on one (1.4 MB a KITTI frame, 4.3 MB at 1600x900).
DECODE_AHEAD = 2


def decoded_ahead(frames: Iterable[Frame], nice: int | None = None) -> Iterator[Frame]:
    """``frames`` iterated (read and decoded) in a thread of its own, up to :data:`DECODE_AHEAD` frames ahead
    of the caller, in order; an error of a frame is raised here when the frames before it were taken. Closing
    the returned iterator stops the thread (which closes ``frames``: a video's capture is released there)."""
    stop = threading.Event()
    ahead: queue.Queue[Frame | _Failure | _End] = queue.Queue(DECODE_AHEAD)
    thread = threading.Thread(target=_read, args=(frames, ahead, stop, nice), name="pedenv-decoder", daemon=True)
    thread.start()
    try:
        while True:
            item = ahead.get()
            if item is _END:
                return
            if isinstance(item, _Failure):
                raise item.exc
            yield item
    finally:
        stop.set()
        thread.join(timeout=5.0)


class _Writer(threading.Thread):
    """Writes results in order; stops at the end marker or at its first error (kept in ``error``)."""

    def __init__(self, write: Callable[[Any], None], done: Callable[[Any], None], stats: PipelineStats,
                 clock: Callable[[], float], config: PipelineConfig) -> None:
        super().__init__(name="pedenv-writer")
        self.items: queue.Queue = queue.Queue(config.write_behind)
        self.nice = config.nice
        self.write, self.done, self.stats, self.clock = write, done, stats, clock
        self.error: BaseException | None = None
        self.failed = threading.Event()

    def run(self) -> None:
        lower_priority(self.nice)
        while True:
            item = self.items.get()
            if item is _END:
                return
            taken, result = item
            try:
                self.write(result)
                self.stats.latencies_s.append(self.clock() - taken)
                self.stats.written += 1
                self.done(result)
            except BaseException as exc:  # noqa: BLE001 - raised in the calling thread
                self.error = exc
                self.failed.set()
                return


class _RealtimeClock:
    """When each frame arrives at the recording's rate, and whether the model was busy then."""

    def __init__(self, clock: Callable[[], float], sleep: Callable[[float], None]) -> None:
        self.clock, self.sleep = clock, sleep
        self.origin: tuple[float, float] | None = None  # (wall clock, timestamp) of the first frame
        self.idle_since = -np.inf  # when the model last finished a frame

    def take(self, frame: Frame) -> float | None:
        """The wall-clock time ``frame`` arrives (after waiting for it), or None to drop it."""
        if self.origin is None:
            self.origin = (self.clock(), frame.timestamp)
        due = self.origin[0] + (frame.timestamp - self.origin[1])
        if due < self.idle_since:
            return None  # it arrived while the model was busy
        wait = due - self.clock()
        if wait > 0:
            self.sleep(wait)
        return due


def run_frames(frames: Iterable[Frame], step: Callable[[Frame], Any], write: Callable[[Any], None], *,
               config: PipelineConfig | None = None,
               done: Callable[[Any], None] = lambda result: None,  # noqa: ARG005 - no progress to report
               stats: PipelineStats | None = None, clock: Callable[[], float] = time.monotonic,
               sleep: Callable[[float], None] = time.sleep) -> PipelineStats:
    """Run ``step`` on each of ``frames`` and ``write`` each result, pipelined (module doc).

    ``done(result)`` is called in the writer thread after ``write`` (a progress bar).
    ``stats``: filled as the run goes (also when it stops with an error); a new one if None.
    ``clock`` and ``sleep`` (seconds) pace ``realtime`` runs. Returns the :class:`PipelineStats`;
    raises the first error of a stage once every finished result is written. numpy's BLAS runs
    :data:`BLAS_THREADS` threads meanwhile (as it was again after).
    """
    with threadpool_limits(limits=BLAS_THREADS, user_api="blas"):
        return _run_frames(frames, step, write, config or PipelineConfig(), done, stats, clock, sleep)


def _run_frames(frames: Iterable[Frame], step: Callable[[Frame], Any], write: Callable[[Any], None],
                config: PipelineConfig, done: Callable[[Any], None], stats: PipelineStats | None,
                clock: Callable[[], float], sleep: Callable[[float], None]) -> PipelineStats:
    """:func:`run_frames`' loop."""
    stats = stats if stats is not None else PipelineStats()
    stop = threading.Event()
    inbox: queue.Queue[Frame | _Failure | _End] = queue.Queue(config.read_ahead)
    reader = threading.Thread(target=_read, args=(frames, inbox, stop, config.nice), name="pedenv-reader", daemon=True)
    writer = _Writer(write, done, stats, clock, config)
    pace = _RealtimeClock(clock, sleep) if config.realtime else None
    start = None
    reader.start()
    writer.start()
    try:
        while True:
            item = _next(inbox, writer)
            if item is _END:
                break
            if isinstance(item, _Failure):
                raise item.exc
            taken = pace.take(item) if pace is not None else clock()
            if taken is None:
                stats.dropped += 1
                continue
            start = taken if start is None else start
            stats.taken += 1
            result = step(item)
            if not _put(writer.items, (taken, result), writer.failed):
                break
            if pace is not None:
                pace.idle_since = clock()  # busy until the result is handed on
    finally:
        stop.set()
        _finish(writer)
        reader.join(timeout=5.0)
        stats.wall_s = clock() - start if start is not None else 0.0
    if writer.error is not None:
        raise writer.error
    return stats


def _next(inbox: queue.Queue[Frame | _Failure | _End], writer: _Writer) -> Frame | _Failure | _End:
    """The next frame (or end or failure) of the reader; stops early when the writer failed."""
    while not writer.failed.is_set():
        try:
            return inbox.get(timeout=_POLL_S)
        except queue.Empty:
            continue
    return _END


def _finish(writer: _Writer) -> None:
    """Let the writer write what it holds, then stop it (it stops by itself after an error)."""
    _put(writer.items, _END, writer.failed)
    while writer.is_alive():
        writer.join(timeout=_POLL_S)
