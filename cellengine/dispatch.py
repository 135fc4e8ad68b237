"""Running many independent compiles: in this process, in local worker processes, or on a
Ray cluster, with the same answers in the same order."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from functools import partial
from pathlib import Path
from typing import TypeVar

from cellengine.workers import Crashed, Raised, run_tasks

T = TypeVar("T")
R = TypeVar("R")


def dispatch(
    tasks: Sequence[tuple[Path, T]],
    local: Callable[[T], R],
    remote: Callable[[T], R],
    jobs: int,
    cluster: str | None = None,
    timeout: float | None = None,
) -> Iterator[tuple[int, R | Crashed | Raised]]:
    """(index, answer) for each (file, arg) of ``tasks``: ``remote(arg)`` on the Ray
    ``cluster`` with the file's folder sent along, else ``local(arg)`` in ``jobs`` worker
    processes (in this process for one job or one task, without a ``timeout``). A task
    still running after ``timeout`` seconds is stopped: a :class:`Crashed` saying so."""
    if cluster is not None:
        from cellengine.cluster import on_cluster

        fn = remote if timeout is None else partial(limited, remote, timeout)
        yield from on_cluster(cluster, tasks, fn)
    elif timeout is not None or (jobs > 1 and len(tasks) > 1):
        import cellengine.pipeline  # noqa: F401  imported once, before the workers fork

        yield from run_tasks(local, [arg for _, arg in tasks], jobs, timeout)
    else:
        for k, (_, arg) in enumerate(tasks):
            yield k, local(arg)


def limited(fn: Callable[[T], R], timeout: float, arg: T) -> R | Crashed:
    """``fn(arg)`` in a worker process of its own, stopped after ``timeout`` seconds (a
    task on a cluster node: its own time limit); what it raised is raised here."""
    ((_, answer),) = run_tasks(fn, [arg], 1, timeout)
    if isinstance(answer, Raised):
        raise answer.error or RuntimeError(answer.text)
    return answer
