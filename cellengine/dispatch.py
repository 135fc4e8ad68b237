"""Running many independent compiles: in this process, in local worker processes, or on a
Ray cluster, with the same answers in the same order."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
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
) -> Iterator[tuple[int, R | Crashed | Raised]]:
    """(index, answer) for each (file, arg) of ``tasks``: ``remote(arg)`` on the Ray
    ``cluster`` with the file's folder sent along, else ``local(arg)`` in ``jobs`` worker
    processes (in this process for one job or one task)."""
    if cluster is not None:
        from cellengine.cluster import on_cluster

        yield from on_cluster(cluster, tasks, remote)
    elif jobs > 1 and len(tasks) > 1:
        import cellengine.pipeline  # noqa: F401  imported once, before the workers fork

        yield from run_tasks(local, [arg for _, arg in tasks], jobs)
    else:
        for k, (_, arg) in enumerate(tasks):
            yield k, local(arg)
