"""Worker processes: every task answered once, a dead worker's task reported, the rest run."""

from __future__ import annotations

import os
import signal
import time
from collections.abc import Callable

import pytest

from cellengine.workers import Crashed, Raised, run_tasks


def _square_or_die(x: int) -> int:
    if x == 3:
        os.kill(os.getpid(), signal.SIGKILL)
    if x == 5:
        raise ValueError("five")
    return x * x


def test_every_task_answered_once_with_its_index() -> None:
    got = dict(run_tasks(lambda x: x * x, list(range(10)), jobs=2))
    assert got == {i: i * i for i in range(10)}


def test_a_killed_worker_is_its_task_only() -> None:
    got = dict(run_tasks(_square_or_die, list(range(8)), jobs=2))
    assert sorted(got) == list(range(8))
    assert got[3] == Crashed.of_exit(-signal.SIGKILL)
    assert str(got[3]) == "its worker process was killed by SIGKILL"
    raised = got[5]
    assert isinstance(raised, Raised) and isinstance(raised.error, ValueError)
    assert "ValueError: five" in raised.text
    assert {i: v for i, v in got.items() if i not in (3, 5)} == {
        i: i * i for i in (0, 1, 2, 4, 6, 7)
    }


def test_a_result_that_does_not_pickle_is_said() -> None:
    ((index, got),) = list(run_tasks(lambda _: lambda: None, [0], jobs=1))
    assert index == 0 and isinstance(got, Raised) and got.error is None
    assert "pickle" in got.text.lower()


def test_a_worker_that_exits_is_reported_with_its_status() -> None:
    got = dict(run_tasks(lambda x: os._exit(7) if x else x, [0, 1, 0], jobs=1))
    assert got[1] == Crashed.of_exit(7)
    assert str(got[1]) == "its worker process exited with status 7 before answering"
    assert got[0] == 0 and got[2] == 0


@pytest.mark.parametrize("jobs", [1, 3])
def test_no_tasks_no_workers(jobs: int) -> None:
    assert list(run_tasks(lambda x: x, [], jobs)) == []


def _slow_at_1(x: int) -> int:
    if x == 1:
        time.sleep(30)
    return x


def test_a_task_past_its_time_is_stopped_and_the_rest_run() -> None:
    t0 = time.monotonic()
    got = dict(run_tasks(_slow_at_1, [0, 1, 2, 3], jobs=1, timeout=1.0))
    assert time.monotonic() - t0 < 20
    assert got == {0: 0, 1: Crashed("it took longer than the 1 s allowed"), 2: 2, 3: 3}


def test_a_worker_past_its_memory_retires_and_the_next_task_gets_a_fresh_one() -> None:
    got = dict(run_tasks(lambda _: os.getpid(), [0, 1, 2], jobs=1, retire_bytes=0))
    assert len(set(got.values())) == 3  # a process each, none reported as crashed
    kept = dict(run_tasks(lambda _: os.getpid(), [0, 1, 2], jobs=1))
    assert len(set(kept.values())) == 1  # under the default: one worker for all


def _holding(mib: int) -> Callable[[int], int]:
    def task(_: int) -> int:
        held.append(b"\x01" * (mib << 20))  # written, so resident and the worker's own
        return os.getpid()

    held: list[bytes] = []
    return task


def test_memory_shared_with_the_parent_is_not_the_workers() -> None:
    parent = b"\x01" * (300 << 20)  # a large parent: its workers start as large
    kept = dict(run_tasks(lambda _: os.getpid(), [0, 1, 2], jobs=1, retire_bytes=200 << 20))
    assert len(set(kept.values())) == 1
    grown = dict(run_tasks(_holding(250), [0, 1, 2], jobs=1, retire_bytes=200 << 20))
    assert len(set(grown.values())) == 3
    del parent
