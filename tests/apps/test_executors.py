"""The serial and Ray executors: results per item, failures per item, one cached object per process."""

import os
import resource
import socket

import pytest

from pedenv.apps import executors
from pedenv.apps.executors import RayExecutor, SerialExecutor, check_reachable, create_executor
from pedenv.errors import InputError


def square_or_fail(item, context):
    """A task: item squared; item 3 is bad data; reports its frames as it goes."""
    context.report(0, 2)
    if item == 3:
        raise InputError(f"item {item}: bad data")
    context.report(2, 2)
    return item * item * context.shared["factor"]


def process_and_session(item, context):
    """A task returning its process and the id of the object it cached there (a pose session)."""
    session = context.cached("session", object)
    return os.getpid(), id(session)


def die_once(item, context):
    """A task whose first attempt kills its worker process; the retry finds the marker and succeeds."""
    marker = context.shared["folder"] + f"/{item}.tried"
    if not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(1)
    return item


def _outcomes(executor, task, items, **kwargs):
    return {item: (value, error) for item, value, error in executor.run(task, items, **kwargs)}


def test_serial_runs_every_item_and_reports_the_failed_one():
    progress = []
    with SerialExecutor() as ex:
        out = _outcomes(ex, square_or_fail, [1, 2, 3, 4], shared={"factor": 10},
                        on_progress=lambda item, done, total: progress.append((item, done, total)))
    assert {k: v for k, (v, e) in out.items() if e is None} == {1: 10, 2: 40, 4: 160}
    assert isinstance(out[3][1], InputError) and "item 3: bad data" in str(out[3][1])
    assert (4, 2, 2) in progress and (3, 0, 2) in progress and (3, 2, 2) not in progress


def test_serial_caches_one_object_per_run():
    with SerialExecutor() as ex:
        out = _outcomes(ex, process_and_session, ["a", "b", "c"])
    assert len({v for v, _ in out.values()}) == 1


@pytest.mark.ray
def test_ray_runs_every_item_and_reports_the_failed_one_with_its_own_error(ray_session):
    progress = []
    with RayExecutor(workers=2) as ex:
        out = _outcomes(ex, square_or_fail, [1, 2, 3, 4], shared={"factor": 10},
                        on_progress=lambda item, done, total: progress.append((item, done, total)))
    assert {k: v for k, (v, e) in out.items() if e is None} == {1: 10, 2: 40, 4: 160}
    assert isinstance(out[3][1], InputError) and "item 3: bad data" in str(out[3][1])
    assert {(i, 2, 2) for i in (1, 2, 4)} <= set(progress)
    assert ray_session.is_initialized()  # the session's Ray: used, not shut down


@pytest.mark.ray
def test_ray_caches_one_object_per_worker_process(ray_session):
    with RayExecutor(workers=2) as ex:
        out = _outcomes(ex, process_and_session, list(range(8)))
    by_process: dict = {}
    for (pid, session), _ in out.values():
        by_process.setdefault(pid, set()).add(session)
    assert all(len(sessions) == 1 for sessions in by_process.values())
    assert len(by_process) <= 8


@pytest.mark.ray
def test_ray_retries_an_item_whose_worker_died(ray_session, tmp_path):
    with RayExecutor(workers=2, max_retries=2) as ex:
        out = _outcomes(ex, die_once, ["a", "b"], shared={"folder": str(tmp_path)})
    assert out == {"a": ("a", None), "b": ("b", None)}


@pytest.mark.ray
def test_ray_reports_an_item_whose_worker_keeps_dying(ray_session, tmp_path):
    with RayExecutor(workers=1, max_retries=0) as ex:
        out = _outcomes(ex, die_once, ["a"], shared={"folder": str(tmp_path)})
    from ray.exceptions import WorkerCrashedError

    value, error = out["a"]
    assert value is None and isinstance(error, WorkerCrashedError)


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("address, message", [
    ("localhost", "must be HOST:PORT"),
    ("10.0.0.1:port", "must be HOST:PORT"),
    (None, "is not reachable"),
])
def test_an_unreachable_or_malformed_address_is_one_clear_error(address, message):
    address = address or f"127.0.0.1:{_closed_port()}"
    with pytest.raises(InputError, match=message) as info:
        check_reachable(address)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("name, options, message", [
    ("dask", {}, "unknown executor 'dask'; valid: serial, ray"),
    ("serial", {"address": "10.0.0.1:6379"}, "--address applies to --executor ray"),
    ("ray", {"workers": 0}, r"workers must be an integer in \[1, 1024\]"),
    ("ray", {"workers": 100_000_000}, r"workers must be an integer in \[1, 1024\], got 100000000"),
    ("ray", {"object_store_memory": 10}, r"--object-store-memory must be at least 78643200 bytes \(Ray's minimum\), "
                                         "got 10"),
])
def test_create_executor_refuses_bad_options(name, options, message):
    with pytest.raises(InputError, match=message):
        create_executor(name, **options)


def test_the_object_store_fits_the_machine_and_an_address_space_limit(monkeypatch):
    """Ray's own default store is 30 % of memory, mapped at start: under ``ulimit -v`` that broke the start."""
    low, high = executors.OBJECT_STORE_RANGE
    assert low <= executors.default_object_store_bytes() <= high
    monkeypatch.setattr(resource, "getrlimit", lambda _: (8_000_000 * 1024, resource.RLIM_INFINITY))
    assert executors.default_object_store_bytes() <= 2_048_000_000  # a quarter of the 8 GB limit
    executors.check_object_store(executors.default_object_store_bytes())
    with pytest.raises(InputError) as info:
        create_executor("ray", object_store_memory=4 * 2**30)
    assert str(info.value) == ("a Ray object store of 4.00 GiB does not fit the address-space limit (ulimit -v) of "
                               "7.63 GiB: give --object-store-memory at most 2048000000 bytes, or raise the limit")
