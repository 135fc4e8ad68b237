"""Best-first enumeration of product spaces whose cost is a sum over their coordinates.

A skill's ways are the product of its free parameters (a sliding angle times tips times stops
...): hundreds of thousands per guide, of which the compiler mostly takes the first few.
Sorting the whole product costs its size every time; this yields the same order lazily.

The combinations form a tree: a combination's parent has its last advanced coordinate (the
last one not at its first value) one value back, so a combination's subtree is every
combination that agrees with it on the coordinates before that one. When the caller knows a
combination is dead because of its first few coordinates alone (a screen that failed for
them), the subtrees that keep those coordinates are dead too and are never built: a guide
whose tips cannot approach it is refused without walking the stand-backs of every tip.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Iterator, Sequence
from typing import Any

Dims = Sequence[Sequence[Any]]  # a group: its dimensions, each the values it may take
# (group, combination) -> None when it may be taken, else the last coordinate its being dead
# depends on (every combination agreeing with it up to there is dead too)
Prune = Callable[[int, tuple[Any, ...]], int | None]


def best_first(
    groups: Sequence[Dims],
    cost: Callable[[int, tuple[Any, ...]], float],
    share: Callable[[int, int, Any], float],
    prune: Prune | None = None,
    ties: Sequence[int] | None = None,
) -> Iterator[tuple[int, tuple[Any, ...]]]:
    """Every (group index, combination) of ``groups`` (a combination takes one value of each
    of the group's dims) by ``cost(group, combination)``, ties in the order the groups and
    their dims list them (the dims in the order ``ties`` lists their indices, if given): the
    order of sorting the whole product by (cost, position), at O(log) per way taken.
    ``cost`` must grow with ``share(group, dim, value)`` in each coordinate (a constant per
    group plus the shares' sum). ``prune``: asked before a combination is yielded and again
    when the caller comes back from it; a dead combination is not yielded, and the
    combinations that agree with it up to the coordinate it names are left out."""
    heap: list[tuple[float, int, tuple[int, ...], tuple[int, ...], int, tuple[Any, ...]]] = []
    orders: list[tuple[tuple[int, ...], ...]] = []

    def push(i: int, pos: tuple[int, ...], last: int) -> None:
        idx = tuple(o[p] for o, p in zip(orders[i], pos, strict=True))
        combo = tuple(d[k] for d, k in zip(groups[i], idx, strict=True))
        tie = idx if ties is None else tuple(idx[j] for j in ties)
        heapq.heappush(heap, (cost(i, combo), i, tie, pos, last, combo))

    def order(i: int, j: int, d: Sequence[Any]) -> tuple[int, ...]:
        return tuple(sorted(range(len(d)), key=lambda k: (share(i, j, d[k]), k)))

    for i, dims in enumerate(groups):
        orders.append(tuple(order(i, j, d) for j, d in enumerate(dims)))
        if all(len(d) > 0 for d in dims):
            push(i, (0,) * len(dims), 0)
    while heap:
        _, i, _, pos, last, combo = heapq.heappop(heap)
        dead = None if prune is None else prune(i, combo)
        if dead is None:
            yield i, combo
            dead = None if prune is None else prune(i, combo)
        # each combination is pushed once, by the one with its last advanced coordinate one
        # back; a coordinate advanced never lowers the cost. Past the coordinate a dead one
        # names, its children (and theirs) keep what made it dead.
        top = len(pos) if dead is None else min(len(pos), dead + 1)
        for j in range(last, top):
            if pos[j] + 1 < len(groups[i][j]):
                push(i, (*pos[:j], pos[j] + 1, *pos[j + 1 :]), j)
