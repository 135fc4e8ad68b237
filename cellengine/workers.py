"""Tasks run in worker processes, robust to a worker that dies mid-task.

``concurrent.futures.ProcessPoolExecutor`` fails every pending task once one worker is
killed (BrokenProcessPool) and ``multiprocessing.Pool`` waits forever for the lost one; here
the task a dead worker held is reported as :class:`Crashed`, a new worker takes its place
and the other tasks still run.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import signal
import time
import traceback
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from multiprocessing.connection import Connection, wait
from typing import Any, Generic, TypeVar

T = TypeVar("T")
R = TypeVar("R")
# a worker holding more after a task is replaced by a fresh one (a board's search can take
# a few GB; a few hundred boards in one long-lived worker would keep the most any took)
RETIRE_BYTES = 1 << 30


@dataclass(frozen=True)
class Crashed:
    """A task whose worker ended before answering (killed, out of memory, a fault in a
    compiled library): why, as a message's end ("its worker process was killed by ...")."""

    why: str

    @classmethod
    def of_exit(cls, code: int | None) -> Crashed:
        if code is not None and code < 0:
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = f"signal {-code}"
            return cls(f"its worker process was killed by {name}")
        return cls(f"its worker process exited with status {code} before answering")

    def __str__(self) -> str:
        return self.why


@dataclass(frozen=True)
class Raised:
    """A task that raised: the exception when it could be sent back, and its traceback."""

    error: BaseException | None
    text: str


@dataclass
class _Worker(Generic[T]):
    process: Any  # multiprocessing's Process (the context's own class)
    conn: Connection
    task: int | None = None
    started: float = 0.0  # when it was given its task (time.monotonic)


def default_jobs() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def run_tasks(
    fn: Callable[[T], R],
    tasks: Sequence[T],
    jobs: int,
    timeout: float | None = None,
    retire_bytes: int = RETIRE_BYTES,
) -> Iterator[tuple[int, R | Crashed | Raised]]:
    """``fn(task)`` for every task in up to ``jobs`` worker processes, yielding (index,
    result) as each ends, in the order they end; :class:`Raised` when ``fn`` raised,
    :class:`Crashed` when its worker died or was stopped after ``timeout`` seconds on the
    task. A worker past ``retire_bytes`` of memory after a task is replaced. ``fn`` and
    the tasks must be picklable where processes are spawned rather than forked."""
    ctx = _context()
    pending = list(range(len(tasks)))[::-1]  # popped from the end: first task first
    workers: list[_Worker[T]] = []
    try:
        for _ in range(min(jobs, len(tasks))):
            workers.append(_start(ctx, fn, retire_bytes))
        for w in workers:
            _give(w, tasks, pending)
        while any(w.task is not None for w in workers):
            busy = [w for w in workers if w.task is not None]
            left = None if timeout is None else min(w.started + timeout for w in busy)
            ready = wait(
                [w.conn for w in busy] + [w.process.sentinel for w in busy],
                None if left is None else max(0.0, left - time.monotonic()),
            )
            for w in busy:
                over = timeout is not None and time.monotonic() > w.started + timeout
                if w.conn not in ready and w.process.sentinel not in ready and not over:
                    continue
                index = w.task
                assert index is not None
                result: R | Crashed | Raised
                if w.conn in ready or w.process.sentinel in ready:
                    result, gone = _answer(w)
                else:  # still at it: stopped
                    w.process.kill()
                    w.process.join()
                    result, gone = Crashed(f"it took longer than the {timeout:g} s allowed"), True
                if gone:  # another worker takes its place
                    w.conn.close()
                    workers[workers.index(w)] = w = _start(ctx, fn, retire_bytes)
                w.task = None
                yield index, result
                _give(w, tasks, pending)
    finally:
        for w in workers:
            _stop(w)


def _answer(w: _Worker[T]) -> tuple[Any, bool]:
    """The worker's answer, and whether it is gone (died before answering, or retired)."""
    try:
        answer, retired = w.conn.recv()
    except (EOFError, OSError):
        w.process.join()
        return Crashed.of_exit(w.process.exitcode), True
    if retired:
        w.process.join()
    return answer, retired


def _context() -> Any:
    # fork shares what the parent has imported (the motion stack: ~0.3 s a worker otherwise)
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("fork" if "fork" in methods else "spawn")


def _start(ctx: Any, fn: Callable[[T], R], retire_bytes: int) -> _Worker[T]:
    parent, child = ctx.Pipe()
    process = ctx.Process(target=_serve, args=(fn, child, retire_bytes), daemon=True)
    process.start()
    child.close()
    return _Worker(process, parent)


def _give(w: _Worker[T], tasks: Sequence[T], pending: list[int]) -> None:
    if pending:
        w.task = pending.pop()
        w.started = time.monotonic()
        w.conn.send(tasks[w.task])


def _stop(w: _Worker[T]) -> None:
    with contextlib.suppress(OSError):  # gone already
        w.conn.send(None)
    w.conn.close()
    w.process.join(timeout=5)
    if w.process.is_alive():
        w.process.kill()
        w.process.join()


def _serve(fn: Callable[[Any], Any], conn: Connection, retire_bytes: int) -> None:
    """A worker's loop: a task in, its result out (and whether it retires), until None. A
    worker whose memory passed ``retire_bytes`` retires after answering: what a large
    compile took is given back, where a long-lived process would keep it (the allocator
    rarely returns it), and a fresh worker takes the next task."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    while True:
        try:
            task = conn.recv()
        except EOFError:
            return
        if task is None:
            return
        try:
            answer: Any = fn(task)
        except Exception as e:  # sent back whole: the parent decides what it means
            answer = Raised(e, traceback.format_exc())
        retire = _private_bytes() > retire_bytes
        try:
            conn.send((answer, retire))
        except Exception as e:  # the result or the exception would not pickle
            text = f"{type(e).__name__}: {e}\n{traceback.format_exc()}"
            conn.send((Raised(None, text), retire))
        if retire:
            return


def _private_bytes() -> int:
    """The memory only this process holds: what its exit gives back. Pages still shared
    with the parent since the fork are not counted (a worker forked from a large process
    starts with the parent's resident size); 0 where /proc is not there: it never retires."""
    try:
        with open("/proc/self/smaps_rollup") as f:
            fields = dict(line.split(":", 1) for line in f if ":" in line)
        kib = int(fields["Private_Clean"].split()[0]) + int(fields["Private_Dirty"].split()[0])
        return kib * 1024
    except (OSError, ValueError, KeyError, IndexError):
        return 0
