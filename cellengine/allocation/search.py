"""Solving the built problem: which option of each task, in which order, least travel.

A solution is a global order of the tasks (a linear extension of ``after``) and one option
per task. Each robot's travel is its path through its actions in that order; the cost sums
them. ``exact`` is an A* over (done tasks, each robot's location, spots taken) with an
admissible bound, so the first complete state it takes is a minimum; ``heuristic`` is greedy
construction, re-insertion of single tasks (order and option) until nothing improves, and
seeded shakes of the best followed by the same improvement (iterated local search).
"""

from __future__ import annotations

import heapq
import itertools
import math
import random
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from cellengine.allocation.model import Loc, distance
from cellengine.allocation.options import Expanded

EPS = 1e-9


@dataclass(frozen=True)
class Leg:
    robot: int
    entry: int  # location ids
    exit: int


@dataclass(frozen=True)
class Opt:
    legs: tuple[Leg, ...]
    internal: float
    spot: int  # bit of the spot it takes, -1 for none


@dataclass(frozen=True)
class Compiled:
    """The search's view: integer ids, precedence bitmasks, a distance table."""

    ids: tuple[str, ...]
    pred: tuple[int, ...]
    succ: tuple[int, ...]
    opts: tuple[tuple[Opt, ...], ...]
    dist: tuple[tuple[float, ...], ...]
    starts: tuple[int, ...]
    ends: tuple[int, ...]  # -1: the robot stays where its last task leaves it


@dataclass(frozen=True)
class Solution:
    order: tuple[int, ...]
    choice: tuple[int, ...]  # option index per task
    cost: float


def compile_problem(ex: Expanded) -> Compiled:
    locs: dict[Loc, int] = {}
    spots: dict[object, int] = {}

    def lid(loc: Loc) -> int:
        return locs.setdefault(loc, len(locs))

    robots = [r.name for r in ex.problem.robots]
    starts = tuple(lid((r.start,)) for r in ex.problem.robots)
    ends = tuple(-1 if r.end is None else lid((r.end,)) for r in ex.problem.robots)
    ids = tuple(t.id for t in ex.tasks)
    index = {t: i for i, t in enumerate(ids)}
    pred = tuple(sum(1 << index[a] for a in t.after) for t in ex.tasks)
    succ = tuple(sum(1 << j for j, p in enumerate(pred) if p >> i & 1) for i in range(len(ids)))
    opts = []
    for t in ex.tasks:
        row = []
        for o in ex.options[t.id]:
            legs = tuple(Leg(robots.index(r), lid(o.entry(r)), lid(o.exit(r))) for r in o.alliance)
            spot = -1 if o.spot is None else spots.setdefault(o.spot, len(spots))
            row.append(Opt(legs, sum(o.internal(r) for r in o.alliance), spot))
        opts.append(tuple(row))
    table = list(locs)
    dist = tuple(tuple(distance(a, b) for b in table) for a in table)
    return Compiled(ids, pred, succ, tuple(opts), dist, starts, ends)


def evaluate(c: Compiled, order: tuple[int, ...], choice: tuple[int, ...]) -> float:
    pos = list(c.starts)
    total = 0.0
    for t in order:
        o = c.opts[t][choice[t]]
        total += o.internal
        for leg in o.legs:
            total += c.dist[pos[leg.robot]][leg.entry]
            pos[leg.robot] = leg.exit
    return total + _home(c, pos)


def _home(c: Compiled, pos: Sequence[int]) -> float:
    """The robots' way back to their end positions, where they have one."""
    return sum(c.dist[p][e] for p, e in zip(pos, c.ends, strict=True) if e >= 0)


def _step(c: Compiled, o: Opt, pos: tuple[int, ...]) -> tuple[float, tuple[int, ...]]:
    cost = o.internal
    new = list(pos)
    for leg in o.legs:
        cost += c.dist[pos[leg.robot]][leg.entry]
        new[leg.robot] = leg.exit
    return cost, tuple(new)


# --- heuristic -------------------------------------------------------------------------


def _moves(
    c: Compiled, done: int, spots: int, pos: tuple[int, ...]
) -> Iterator[tuple[int, int, Opt, float, tuple[int, ...]]]:
    """Each task ready after ``done`` (its predecessors done) in each of its options whose
    spot is free in ``spots``: (task, option index, option, its cost from ``pos``, the
    robots' positions after it)."""
    for t in range(len(c.ids)):
        if done >> t & 1 or c.pred[t] & ~done:
            continue
        for k, o in enumerate(c.opts[t]):
            if o.spot >= 0 and spots >> o.spot & 1:
                continue
            cost, new = _step(c, o, pos)
            yield t, k, o, cost, new


def greedy(c: Compiled) -> Solution:
    """Repeatedly the ready task and option that adds least travel (first on ties), never
    taking a spot that another relocation left to do would then lack."""
    n = len(c.ids)
    if not _spots_fit(c, 0, 0):
        moves = [c.ids[t] for t in range(n) if any(o.spot >= 0 for o in c.opts[t])]
        raise ValueError(f"relocations {', '.join(moves)} need a free spot each; too few")
    done = spots = 0
    pos = c.starts
    order: list[int] = []
    choice = [0] * n
    while len(order) < n:
        best: tuple[float, int, int, tuple[int, ...]] | None = None
        for t, k, o, cost, new in _moves(c, done, spots, pos):
            if best is not None and cost >= best[0] - EPS:
                continue
            if o.spot < 0 or _spots_fit(c, done | 1 << t, spots | 1 << o.spot):
                best = (cost, t, k, new)
        assert best is not None  # some task is ready (no cycle) and spots still fit
        _, t, k, pos = best
        o = c.opts[t][k]
        spots |= (1 << o.spot) if o.spot >= 0 else 0
        done |= 1 << t
        order.append(t)
        choice[t] = k
    return Solution(tuple(order), tuple(choice), evaluate(c, tuple(order), tuple(choice)))


def _spots_fit(c: Compiled, done: int, taken: int) -> bool:
    """Whether every relocation not done yet can still have a free spot of its own
    (augmenting paths: a bipartite matching of relocations to spots)."""
    owner: dict[int, int] = {}

    def place(t: int, seen: set[int]) -> bool:
        for o in c.opts[t]:
            if o.spot < 0 or taken >> o.spot & 1 or o.spot in seen:
                continue
            seen.add(o.spot)
            if o.spot not in owner or place(owner[o.spot], seen):
                owner[o.spot] = t
                return True
        return False

    todo = (t for t in range(len(c.ids)) if not done >> t & 1)
    return all(place(t, set()) for t in todo if any(o.spot >= 0 for o in c.opts[t]))


def improve(c: Compiled, s: Solution, max_passes: int = 100) -> Solution:
    """Take each task out and put it back at its best place and option, until a whole pass
    finds nothing better (or ``max_passes``, which keeps the run bounded and deterministic)."""
    for _ in range(max_passes):
        better = False
        for t in range(len(c.ids)):
            moved = _reinsert(c, s, t)
            if moved.cost < s.cost - EPS:
                s, better = moved, True
        if not better:
            break
    return s


def _reinsert(c: Compiled, s: Solution, t: int) -> Solution:
    rest = tuple(u for u in s.order if u != t)
    base = evaluate(c, rest, s.choice)
    lo = max((i + 1 for i, u in enumerate(rest) if c.pred[t] >> u & 1), default=0)
    hi = min((i for i, u in enumerate(rest) if c.succ[t] >> u & 1), default=len(rest))
    taken = 0
    for u in rest:
        sp = c.opts[u][s.choice[u]].spot
        taken |= (1 << sp) if sp >= 0 else 0
    before, after = _neighbours(c, rest, s.choice)
    best = (s.cost, s.order.index(t), s.choice[t])
    for j in range(lo, hi + 1):
        for k, o in enumerate(c.opts[t]):
            if o.spot >= 0 and taken >> o.spot & 1:
                continue
            cost = base + o.internal
            for leg in o.legs:
                p, q = before[leg.robot][j], after[leg.robot][j]
                cost += c.dist[p][leg.entry]
                if q >= 0:
                    cost += c.dist[leg.exit][q] - c.dist[p][q]
            if cost < best[0] - EPS:
                best = (cost, j, k)
    if best[0] >= s.cost - EPS:
        return s
    _, j, k = best
    order = (*rest[:j], t, *rest[j:])
    choice = tuple(k if u == t else v for u, v in enumerate(s.choice))
    return Solution(order, choice, evaluate(c, order, choice))


def _neighbours(
    c: Compiled, order: tuple[int, ...], choice: tuple[int, ...]
) -> tuple[list[list[int]], list[list[int]]]:
    """Per robot and insertion point j: where the robot is before j, where it goes next
    after j (-1: nowhere)."""
    n, robots = len(order), len(c.starts)
    before = [[c.starts[r]] * (n + 1) for r in range(robots)]
    after = [[-1] * n + [c.ends[r]] for r in range(robots)]
    for j, u in enumerate(order):
        for r in range(robots):
            before[r][j + 1] = before[r][j]
        for leg in c.opts[u][choice[u]].legs:
            before[leg.robot][j + 1] = leg.exit
    for j in range(n - 1, -1, -1):
        u = order[j]
        for r in range(robots):
            after[r][j] = after[r][j + 1]
        for leg in c.opts[u][choice[u]].legs:
            after[leg.robot][j] = leg.entry
    return before, after


def heuristic(c: Compiled, rounds: int = 30, seed: int = 0) -> Solution:
    """Greedy, improved; then ``rounds`` times: shake the best (a few tasks moved to random
    places and options), improve, keep it if cheaper. Seeded, so deterministic."""
    rng = random.Random(seed)
    best = improve(c, greedy(c))
    for _ in range(rounds if len(c.ids) > 1 else 0):
        shaken = _shake(c, best, rng)
        if shaken is not None:
            tried = improve(c, shaken)
            if tried.cost < best.cost - EPS:
                best = tried
    return best


def _shake(c: Compiled, s: Solution, rng: random.Random, moves: int = 3) -> Solution | None:
    """Move a few tasks to random places their precedence allows, with random options; None
    if two relocations end up on one spot."""
    order, choice = list(s.order), list(s.choice)
    for _ in range(moves):
        t = rng.randrange(len(order))
        order.remove(t)
        lo = max((i + 1 for i, u in enumerate(order) if c.pred[t] >> u & 1), default=0)
        hi = min((i for i, u in enumerate(order) if c.succ[t] >> u & 1), default=len(order))
        order.insert(rng.randint(lo, hi), t)
        choice[t] = rng.randrange(len(c.opts[t]))
    spots = [c.opts[t][k].spot for t, k in enumerate(choice) if c.opts[t][k].spot >= 0]
    if len(spots) != len(set(spots)):
        return None
    return Solution(tuple(order), tuple(choice), evaluate(c, tuple(order), tuple(choice)))


# --- exact -----------------------------------------------------------------------------


def lower_bound(c: Compiled) -> float:
    """A cost no mission can beat (the exact search's bound from the start)."""
    return _Bound(c)(0, c.starts)


def exact(c: Compiled, bound: Solution, max_expansions: int) -> Solution | None:
    """A* from nothing done to everything done; ``bound`` (a known solution) prunes, and is
    returned when nothing cheaper exists. None when ``max_expansions`` runs out first."""
    n = len(c.ids)
    full = (1 << n) - 1
    bound_of = _Bound(c)
    Key = tuple[int, tuple[int, ...], int]
    start: Key = (0, c.starts, 0)
    best_g: dict[Key, float] = {start: 0.0}
    parent: dict[Key, tuple[Key, int, int]] = {}
    tie = itertools.count()
    heap = [(bound_of(0, c.starts), next(tie), 0.0, start)]
    expansions = 0
    while heap:
        _, _, g, key = heapq.heappop(heap)
        if g > best_g[key] + EPS:
            continue  # reached again more cheaply since
        done, pos, spots = key
        if done == full:
            return _rebuild(c, parent, key, g)
        expansions += 1
        if expansions > max_expansions:
            return None
        for t, k, o, cost, new in _moves(c, done, spots, pos):
            nxt: Key = (done | 1 << t, new, spots | ((1 << o.spot) if o.spot >= 0 else 0))
            g2 = g + cost + (_home(c, new) if nxt[0] == full else 0.0)
            if g2 >= best_g.get(nxt, float("inf")) - EPS:
                continue
            f2 = g2 + bound_of(nxt[0], new)
            if f2 >= bound.cost - EPS:
                continue  # cannot beat the known solution
            best_g[nxt] = g2
            parent[nxt] = (key, t, k)
            heapq.heappush(heap, (f2, next(tie), g2, nxt))
    return bound


Inbound = tuple[tuple[tuple[tuple[tuple[float, int], ...], ...], ...], ...]


def _inbound(c: Compiled) -> Inbound:
    """Per task, option and leg: the distances from every other task's exits for that robot
    to the leg's entry, nearest first, with the task they come from."""
    n = len(c.ids)
    later = _descendants(c)
    out = []
    for t in range(n):
        per_opt = []
        for o in c.opts[t]:
            per_leg = []
            for leg in o.legs:
                near: dict[int, float] = {}
                for u in range(n):
                    if u == t or later[t] >> u & 1:
                        continue  # a task after t cannot be where t's robot comes from
                    for p in c.opts[u]:
                        for q in p.legs:
                            if q.robot == leg.robot:
                                d = c.dist[q.exit][leg.entry]
                                near[u] = min(near.get(u, d), d)
                per_leg.append(tuple(sorted((d, u) for u, d in near.items())))
            per_opt.append(tuple(per_leg))
        out.append(tuple(per_opt))
    return tuple(out)


def _descendants(c: Compiled) -> list[int]:
    """Per task, the bitmask of tasks that must come after it."""
    later = [0] * len(c.ids)
    changed = True
    while changed:
        changed = False
        for t, succ in enumerate(c.succ):
            grown = succ
            for u in range(len(c.ids)):
                if succ >> u & 1:
                    grown |= later[u]
            if grown != later[t]:
                later[t], changed = grown, True
    return later


class _Bound:
    """Each task left costs at least its cheapest option's internal travel plus, per robot,
    the nearest place that robot can come from: where it is now or the exit of another task
    left that may precede it. Every robot path enters each task once from one of those, so
    this never overestimates. The part that depends only on the tasks done is cached."""

    def __init__(self, c: Compiled) -> None:
        self.c = c
        self.inbound = _inbound(c)
        self.rows: dict[int, list[list[tuple[float, list[tuple[int, int, float]]]]]] = {}

    def __call__(self, done: int, pos: tuple[int, ...]) -> float:
        rows = self.rows.get(done)
        if rows is None:
            rows = self.rows[done] = self._rows(done)
        here = [self.c.dist[p] for p in pos]  # per robot: distances from where it is
        total = 0.0
        for options in rows:
            cheapest = math.inf
            for cost, legs in options:
                for robot, entry, near in legs:
                    d = here[robot][entry]
                    cost += d if d < near else near
                if cost < cheapest:
                    cheapest = cost
            total += cheapest
        return total

    def _rows(self, done: int) -> list[list[tuple[float, list[tuple[int, int, float]]]]]:
        """Per task left, per option: internal travel and, per leg, the nearest exit of
        another task left (inf if none)."""
        rows = []
        for t, opts in enumerate(self.c.opts):
            if done >> t & 1:
                continue
            row = []
            for o, legs_in in zip(opts, self.inbound[t], strict=True):
                near = [next((d for d, u in n if not done >> u & 1), math.inf) for n in legs_in]
                legs = [(g.robot, g.entry, m) for g, m in zip(o.legs, near, strict=True)]
                row.append((o.internal, legs))
            rows.append(row)
        return rows


def _rebuild(
    c: Compiled,
    parent: dict[
        tuple[int, tuple[int, ...], int], tuple[tuple[int, tuple[int, ...], int], int, int]
    ],
    key: tuple[int, tuple[int, ...], int],
    g: float,
) -> Solution:
    order: list[int] = []
    choice = [0] * len(c.ids)
    while key in parent:
        key, t, k = parent[key]
        order.append(t)
        choice[t] = k
    order.reverse()
    return Solution(tuple(order), tuple(choice), evaluate(c, tuple(order), tuple(choice)))
