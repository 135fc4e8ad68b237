"""Best-first enumeration of product spaces whose cost is a sum over their coordinates.

A skill's ways are the product of its free parameters (a sliding angle times tips times stops
...): hundreds of thousands per guide, of which the compiler mostly takes the first few.
Sorting the whole product costs its size every time; this yields the same order lazily.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterator, Sequence
from typing import Any

Dims = Sequence[Sequence[Any]]  # a group: its dimensions, each the values it may take


def best_first(
    groups: Sequence[Dims],
    cost: Callable[[int, tuple[Any, ...]], float],
    share: Callable[[int, int, Any], float],
) -> Iterator[tuple[int, tuple[Any, ...]]]:
    """Every (group index, combination) of ``groups`` (a combination takes one value of each
    of the group's dims) by ``cost(group, combination)``, ties in the order the groups and
    their dims list them: the order of sorting the whole product by (cost, position), at
    O(log) per way taken. ``cost`` must grow with ``share(group, dim, value)`` in each
    coordinate (a constant per group plus the shares' sum)."""
    heap: list[tuple[float, int, tuple[int, ...], tuple[int, ...], int, tuple[Any, ...]]] = []
    orders: list[tuple[tuple[int, ...], ...]] = []

    def push(i: int, pos: tuple[int, ...], last: int) -> None:
        idx = tuple(o[p] for o, p in zip(orders[i], pos, strict=True))
        combo = tuple(d[k] for d, k in zip(groups[i], idx, strict=True))
        heapq.heappush(heap, (cost(i, combo), i, idx, pos, last, combo))

    def order(i: int, j: int, d: Sequence[Any]) -> tuple[int, ...]:
        return tuple(sorted(range(len(d)), key=lambda k: (share(i, j, d[k]), k)))

    for i, dims in enumerate(groups):
        orders.append(tuple(order(i, j, d) for j, d in enumerate(dims)))
        if all(len(d) > 0 for d in dims):
            push(i, (0,) * len(dims), 0)
    while heap:
        _, i, _, pos, last, combo = heapq.heappop(heap)
        yield i, combo
        # each combination is pushed once, by the one with its last advanced coordinate one
        # back; a coordinate advanced never lowers the cost
        for j in range(last, len(pos)):
            if pos[j] + 1 < len(groups[i][j]):
                push(i, (*pos[:j], pos[j] + 1, *pos[j + 1 :]), j)
