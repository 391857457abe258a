"""Where independent units of work (scenes, recordings) run: in this process, or on Ray.

    with create_executor("ray", workers=2) as ex:
        for item, value, error in ex.run(task, items, shared={"dataset": data}, on_progress=show):
            ...

``task(item, context)`` is a module-level function; ``context.shared`` holds the objects
given in ``shared`` (shipped once to each Ray worker through Ray's object store),
``context.cached(key, make)`` keeps an object (a pose network session) for every later
item run by the same process, and ``context.report(done, total)`` counts frames.
``run`` yields ``(item, value, None)`` or ``(item, None, error)`` as the items finish, in
any order: one failing item never stops the others.

The Ray executor uses Ray's own machinery: one remote task per item with ``max_retries``
(a worker process that dies is restarted and its item run again), ``ray.wait`` for
finished items and ``ray.util.queue.Queue`` for frame counts. Without an address it
starts a local Ray with ``workers`` CPUs and shuts it down on the way out, Ctrl-C
included, so no Ray process it started outlives the run; with ``address`` it joins a
running cluster (``ray start --head``) and only disconnects. A local Ray's object store is
sized to the machine (:func:`default_object_store_bytes`) and checked against an address-space
limit (``ulimit -v``) before Ray starts; a start that fails or does not finish within
:data:`RAY_START_TIMEOUT_S` is one line, and every Ray process it left is stopped.
"""

from __future__ import annotations

import contextlib
import os
import resource
import signal
import socket
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path
from typing import Any

from pedenv.errors import InputError, require_extra

#: Executor names of ``--executor``.
EXECUTORS = ("serial", "ray")
#: Times Ray runs an item again after its worker process died (Ray's ``max_retries``).
MAX_RETRIES = 3
#: Seconds between two frame counts a worker sends to the progress bar.
REPORT_INTERVAL_S = 0.5
#: Seconds to wait for a TCP connection to a cluster's address before calling it unreachable.
CONNECT_TIMEOUT_S = 5.0

#: Seconds a local Ray may take to start (10 to 30 s on two busy cores) before the start is
#: given up as hung, with one error line.
RAY_START_TIMEOUT_S = 120
#: Bounds of a local Ray's object store, bytes: Ray's own minimum (75 MiB) and the most pedenv asks
#: for by default. pedenv puts in the store only the shared settings and each item's result
#: (kilobytes to a few megabytes a scene).
OBJECT_STORE_RANGE = (75 * 2**20, 2 * 2**30)
#: Share of an address-space limit (``ulimit -v``) the object store may take: Ray maps it whole,
#: and the driver's own libraries, threads and heap need the rest.
MAX_STORE_SHARE_OF_ADDRESS_SPACE = 0.25

Outcome = tuple[Any, Any, BaseException | None]


def default_object_store_bytes() -> int:
    """A local Ray's object store when none is given: 10 % of the machine's memory, within
    :data:`OBJECT_STORE_RANGE` and :data:`MAX_STORE_SHARE_OF_ADDRESS_SPACE` of an address-space
    limit (Ray's own default, 30 % of memory, is mapped from the start and counts against ``ulimit -v``)."""
    try:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError):
        memory = 8 * 2**30
    low, high = OBJECT_STORE_RANGE
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    if limit != resource.RLIM_INFINITY:
        high = min(high, int(MAX_STORE_SHARE_OF_ADDRESS_SPACE * limit))
    return int(max(min(memory // 10, high), low))


def check_object_store(size: int) -> None:
    """InputError when ``size`` (bytes) is outside Ray's minimum or does not fit the process's
    address-space limit (``ulimit -v``) with room for the rest of the driver."""
    if isinstance(size, bool) or not isinstance(size, int) or size < OBJECT_STORE_RANGE[0]:
        raise InputError(f"--object-store-memory must be at least {OBJECT_STORE_RANGE[0]} bytes (Ray's minimum), "
                         f"got {size!r}")
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    if limit != resource.RLIM_INFINITY and size > MAX_STORE_SHARE_OF_ADDRESS_SPACE * limit:
        raise InputError(f"a Ray object store of {size / 2**30:.2f} GiB does not fit the address-space limit "
                         f"(ulimit -v) of {limit / 2**30:.2f} GiB: give --object-store-memory at most "
                         f"{int(MAX_STORE_SHARE_OF_ADDRESS_SPACE * limit)} bytes, or raise the limit")


class TaskContext:
    """What a task sees: the shared objects, a per-process cache, a frame counter."""

    def __init__(self, shared: dict[str, Any], cache: dict, report: Callable[[int, int], None]) -> None:
        self.shared = shared
        self._cache = cache
        self.report = report

    def cached(self, key: Any, make: Callable[[], Any]) -> Any:
        """The object stored under ``key`` in this process, made by ``make()`` the first time."""
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]


class SerialExecutor:
    """Runs the items one after the other in this process."""

    name = "serial"

    def __enter__(self) -> SerialExecutor:
        return self

    def __exit__(self, *exc: object) -> None:
        return None

    def run(self, task: Callable, items: Iterable, *, shared: dict[str, Any] | None = None,
            on_progress: Callable[[Any, int, int], None] | None = None) -> Iterator[Outcome]:
        cache: dict = {}  # one run: the pose network is loaded once
        for item in items:
            report = (lambda done, total, item=item: on_progress(item, done, total)) if on_progress else _ignore
            try:
                value = task(item, TaskContext(shared or {}, cache, report))
            except Exception as exc:  # noqa: BLE001 - reported per item; Ctrl-C passes through
                yield item, None, exc
            else:
                yield item, value, None


#: Most Ray workers (``--workers``): far above one machine's cores, low enough that a typo
#: (``--workers 100000000``) does not ask Ray for a hundred million CPUs.
MAX_WORKERS = 1024


class RayExecutor:
    """Runs each item as one Ray task on a local Ray (started here) or on a cluster at ``address``.

    workers: CPUs of the local Ray, or the most items in flight on a cluster (default: all
    its CPUs). max_retries: Ray's retries of an item whose worker died. object_store_memory:
    bytes of the local Ray's object store (None: :func:`default_object_store_bytes`).
    """

    name = "ray"

    def __init__(self, *, address: str | None = None, workers: int | None = None, max_retries: int = MAX_RETRIES,
                 object_store_memory: int | None = None) -> None:
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                    or not 1 <= workers <= MAX_WORKERS):
            raise InputError(f"workers must be an integer in [1, {MAX_WORKERS}], got {workers!r}")
        if isinstance(max_retries, bool) or not isinstance(max_retries, int) or max_retries < 0:
            raise InputError(f"max_retries must be an integer >= 0, got {max_retries!r}")
        self.address, self.workers, self.max_retries = address, workers, max_retries
        if object_store_memory is not None and address is None:
            check_object_store(object_store_memory)
        self.object_store_memory = object_store_memory
        self._started = False

    def __enter__(self) -> RayExecutor:
        require_extra("ray", "ray", "--executor ray")
        import ray

        if self.address is None and ray.is_initialized():
            return self  # a Ray this process already runs (a test session): used, left running
        if self.address is not None:
            check_reachable(self.address)
        options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False}
        if self.address is None:
            options["num_cpus"] = self.workers or os.cpu_count() or 1
            options["object_store_memory"] = self.object_store_memory or default_object_store_bytes()
            check_object_store(options["object_store_memory"])  # the default against ulimit -v
        try:
            with _deadline(RAY_START_TIMEOUT_S):
                ray.init(address=self.address, **options)
        except ConnectionError as exc:
            _stop_ray(ray)
            raise InputError(f"cannot join the Ray cluster at {self.address}: {exc}") from None
        except TimeoutError:
            _stop_ray(ray)
            where = f"the Ray cluster at {self.address}" if self.address else "a local Ray"
            raise InputError(f"{where} did not start within {RAY_START_TIMEOUT_S} s (too little memory or "
                             "address space for it? ulimit -v, --object-store-memory); it was stopped") from None
        except BaseException:  # Ctrl-C while Ray starts: stop what has started
            _stop_ray(ray)
            raise
        self._started = True
        return self

    def __exit__(self, *exc: object) -> None:
        if self._started:
            import ray

            ray.shutdown()  # a local Ray is stopped with its raylet and workers; a cluster is only left
            self._started = False

    def run(self, task: Callable, items: Iterable, *, shared: dict[str, Any] | None = None,
            on_progress: Callable[[Any, int, int], None] | None = None) -> Iterator[Outcome]:
        import ray
        from ray.exceptions import RayError, RayTaskError
        from ray.util.queue import Queue

        remote = ray.remote(num_cpus=1, max_retries=self.max_retries)(_run_on_worker)
        refs = {key: ray.put(value) for key, value in (shared or {}).items()}
        queue = Queue(actor_options={"num_cpus": 0}) if on_progress else None  # no CPU slot taken from the tasks
        limit = self.workers or max(int(ray.cluster_resources().get("CPU", 1)), 1)
        waiting: list = list(items)
        pending: dict = {}
        try:
            while waiting or pending:
                while waiting and len(pending) < limit:
                    item = waiting.pop(0)
                    pending[remote.remote(task, item, [refs], queue)] = item  # [refs]: resolved in the worker
                done, _ = ray.wait(list(pending), num_returns=1, timeout=REPORT_INTERVAL_S)
                _drain(queue, on_progress)
                for ref in done:
                    item = pending.pop(ref)
                    try:
                        yield item, ray.get(ref), None
                    except RayTaskError as exc:  # the task raised: its own exception
                        yield item, None, _cause(exc)
                    except RayError as exc:  # the worker died more than max_retries times
                        yield item, None, exc
            _drain(queue, on_progress)
        finally:
            for ref in pending:  # Ctrl-C or a failing consumer: stop what still runs
                ray.cancel(ref, force=True)
            if queue is not None:
                queue.shutdown()


class _deadline:
    """Raises TimeoutError in the main thread after ``seconds`` (SIGALRM; elsewhere: no deadline)."""

    def __init__(self, seconds: int) -> None:
        self.seconds = seconds
        self.armed = threading.current_thread() is threading.main_thread() and hasattr(signal, "SIGALRM")

    def __enter__(self) -> None:
        if self.armed:
            self.previous = signal.signal(signal.SIGALRM, self._expire)
            signal.alarm(self.seconds)

    def _expire(self, *_: object) -> None:
        raise TimeoutError

    def __exit__(self, *exc: object) -> None:
        if self.armed:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, self.previous)


def _stop_ray(ray: Any) -> None:
    """Shut Ray down and end any process this one started that is still alive (a start cut short
    leaves Ray's GCS server and raylet behind)."""
    children = _descendants(os.getpid())
    try:
        ray.shutdown()
    finally:
        _end(children)


def _end(pids: list[int]) -> None:
    """SIGTERM to the processes ``pids`` still alive, SIGKILL to those alive 5 s later."""
    for sig in (signal.SIGTERM, signal.SIGKILL):
        alive = [pid for pid in pids if _alive(pid)]
        for pid in alive:
            with contextlib.suppress(OSError):
                os.kill(pid, sig)
        for _ in range(50):
            if not any(_alive(pid) for pid in alive):
                break
            time.sleep(0.1)


def _descendants(pid: int) -> list[int]:
    """The process ids below ``pid`` (children, theirs, ...), from ``/proc`` (Linux; elsewhere none)."""
    parents: dict[int, list[int]] = {}
    for entry in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = entry.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        parents.setdefault(int(fields[1]), []).append(int(entry.parent.name))
    found, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"  # a zombie has ended


def _cause(exc: BaseException) -> BaseException:
    cause = getattr(exc, "cause", None)
    return cause if isinstance(cause, BaseException) else exc


#: Per worker process: shared objects and what tasks cached (pose network sessions).
_WORKER_CACHE: dict = {}


def _run_on_worker(task: Callable, item: Any, refs: list[dict], queue: Any) -> Any:
    """A Ray task: the shared objects (fetched once per process), then ``task(item, context)``."""
    import ray

    shared = {key: _fetch(ray, ref) for key, ref in refs[0].items()}
    last = [0.0]

    def report(done: int, total: int) -> None:
        now = time.monotonic()
        if queue is not None and (done in (0, total) or now - last[0] >= REPORT_INTERVAL_S):
            last[0] = now
            queue.put_nowait((item, done, total))

    return task(item, TaskContext(shared, _WORKER_CACHE, report))


def _fetch(ray: Any, ref: Any) -> Any:
    key = ("shared", ref.hex())
    if key not in _WORKER_CACHE:
        _WORKER_CACHE[key] = ray.get(ref)
    return _WORKER_CACHE[key]


def _drain(queue: Any, on_progress: Callable | None) -> None:
    if queue is None or on_progress is None:
        return
    for item, done, total in queue.get_nowait_batch(queue.qsize()):
        on_progress(item, done, total)


def _ignore(done: int, total: int) -> None:  # noqa: ARG001 - a progress callback's signature
    """The progress callback of a run without ``on_progress``: ``report(done, total)`` does nothing."""
    return None


def check_reachable(address: str) -> None:
    """InputError in one line unless ``host:port`` accepts a TCP connection (``auto`` and ``ray://`` pass)."""
    if address == "auto" or "://" in address:
        return
    host, sep, port = address.rpartition(":")
    if not sep or not port.isdigit():
        raise InputError(f"Ray address must be HOST:PORT (e.g. 10.0.0.1:6379), 'auto' or ray://HOST:PORT, "
                         f"got {address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S):
            pass
    except OSError as exc:
        raise InputError(f"Ray cluster at {address} is not reachable ({exc.strerror or exc}); start one there with "
                         f"`ray start --head --port {port}` or leave out --address for a local Ray") from None


def create_executor(name: str = "serial", *, address: str | None = None, workers: int | None = None,
                    object_store_memory: int | None = None) -> SerialExecutor | RayExecutor:
    """The executor named ``name`` (:data:`EXECUTORS`); ``address`` and ``workers`` apply to Ray."""
    if name == "serial":
        if address is not None:
            raise InputError("--address applies to --executor ray")
        return SerialExecutor()
    if name == "ray":
        return RayExecutor(address=address, workers=workers, object_store_memory=object_store_memory)
    raise InputError(f"unknown executor {name!r}; valid: {', '.join(EXECUTORS)}")
