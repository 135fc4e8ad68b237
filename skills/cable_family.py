"""The cable-routing skills as a family (:mod:`cellengine.family`): PickCable,
PlaceConnector and RouteCable chained through one :class:`CableState` from the arms' homes,
each step's ways offered to the compiler best first, and the cable released at the end."""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Sequence, Set
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from cellengine.errors import InputError, Problem, StepError, at_step
from cellengine.family import Candidate
from cellengine.program import Segment
from cellengine.skill import Skill
from cellengine.skills import (
    cable_group,
    cable_meaning,
    cable_swap,
    cable_tape,
    cable_tools,
    cable_top,
)
from cellengine.skills.cable import (
    RELEASE,
    PickCable,
    PlaceConnector,
    RouteCable,
    Shared,
    release_ways,
    step_ways,
)
from cellengine.skills.cable_meaning import Finding
from cellengine.skills.cable_state import ANY_BRANCH, CableState
from cellengine.skills.cable_tape import Tape
from cellengine.skills.cable_tools import ChangeTool
from cellengine.world import World

if TYPE_CHECKING:
    from cellengine.context import PlanningContext


class CableFamily:
    name = "cable"
    skills: tuple[type[Skill], ...] = (PickCable, PlaceConnector, RouteCable, ChangeTool, Tape)

    def check(self, world: World, steps: Sequence[Skill]) -> list[Finding]:
        return cable_meaning.check(world, steps) + cable_tape.check(world, steps)

    def plan(self, ctx: PlanningContext, steps: Sequence[Skill]) -> Iterator[Candidate]:
        _picked_once(steps)
        return _from(ctx, steps, 0, CableState.at_home(ctx), {})


def _picked_once(steps: Sequence[Skill]) -> None:
    """A cable is picked from its combs once: a second PickCable would take it from where it
    no longer lies."""
    first: dict[str, int] = {}
    for i, step in enumerate(steps):
        if isinstance(step, PickCable):
            if step.cable in first:
                before = f"steps[{first[step.cable]}]"
                message = f"steps[{i}] PickCable: '{step.cable}' was picked by {before}"
                raise StepError(Problem(message + "; a cable is picked from its combs once"), i)
            first[step.cable] = i


# A guide no way of which can be routed from a state, by (step, guide, CableState.key()):
# the search often comes back to the same state by another way of an earlier step (a
# different grasp that leaves the arms where they were), and finding that out again means
# screening every way of the guide.
Failed = dict[tuple[int, int, tuple[object, ...]], InputError | None]


def _from(
    ctx: PlanningContext, steps: Sequence[Skill], i: int, state: CableState, failed: Failed
) -> Iterator[Candidate]:
    """The candidates for ``steps[i]`` from ``state`` (for a RouteCable, its first guide's);
    after the last step, the release. Planned on the cell with the tools ``state``'s arms
    carry."""
    ctx = ctx.tooled(state.tools)
    if i == len(steps):
        for segments, _ in release_ways(ctx, state):
            yield Candidate(tuple(segments))
        return
    step = steps[i]
    if isinstance(step, Tape):  # it changes the tools it needs itself
        with at_step(i):
            for segments, after in cable_tape.tape_ways(ctx, step, replace(state, step=i)):
                following = functools.partial(_from, ctx, steps, i + 1, after, failed)
                yield Candidate(tuple(segments), then=following)
        return
    if not isinstance(step, ChangeTool):
        with at_step(i):
            need = {a: cable_tools.GRIPPER for a in state.arms}
            fits = cable_tools.fitting(ctx, state, need, f"steps[{i}] {step.skill}")
        if fits:
            yield from _fitted(ctx, steps, i, replace(state, step=i), fits, failed)
            return
    if isinstance(step, RouteCable):
        yield from _route(ctx, steps, i, replace(state, step=i), failed)
        return
    if isinstance(step, ChangeTool):
        # the segments run on three cells (the old tool, none, the new): not narrowed to
        # IK branches here; the changing arm reaches each slot by a transit
        with at_step(i):
            for segments, after in cable_tools.change_ways(ctx, step, replace(state, step=i)):
                following = functools.partial(_from, ctx, steps, i + 1, after, failed)
                yield Candidate(tuple(segments), then=following)
        return

    # a PickCable decides which arm holds the connector end, a PlaceConnector which arm routes
    # (the other one, or the connector arm after a hand-over): a guide out of the routing
    # arm's reach (errors that blame "arms") comes back to the latest of them, to the other arm
    def decides(after: CableState) -> dict[str, str]:
        if isinstance(step, PickCable):
            return {"arms": f"{after.connector_arm} holds the connector"}
        return {"arms": f"{after.routing_arm} routes"}

    def then(after: CableState) -> Iterator[Candidate]:
        return _from(ctx, steps, i + 1, after, failed)

    yield from _chosen(ctx, i, step, state, step_ways(ctx, steps, i, state), then, decides)


def _fitted(
    ctx: PlanningContext,
    steps: Sequence[Skill],
    i: int,
    state: CableState,
    fits: dict[str, str],
    failed: Failed,
) -> Iterator[Candidate]:
    """The tool change ``steps[i]`` needs first (the first of ``fits``), then the step (or the
    next change it needs) from the state it leaves."""
    arm, tool = next(iter(fits.items()))
    label = f"ChangeTool {arm} (for {steps[i].skill})"
    where = f"steps[{i}] {steps[i].skill}"
    with at_step(i):
        for segments, after in cable_tools.released_change(ctx, state, arm, tool, where, label):
            then = functools.partial(_from, ctx, steps, i, after, failed)
            yield Candidate(tuple(segments), then=then)


def _route(
    ctx: PlanningContext, steps: Sequence[Skill], i: int, state: CableState, failed: Failed
) -> Iterator[Candidate]:
    """RouteCable ``steps[i]``: its first guide's candidates; for a harness's branch not held
    yet, first the ways to take the group at the connector (cable_group), each a choice."""
    step = steps[i]
    assert isinstance(step, RouteCable)
    with at_step(i):
        taking = cable_group.group_ways(ctx, step, state)
    if taking is None:
        yield from _guide(ctx, steps, i, state, 0, failed)
        return

    def then(after: CableState) -> Iterator[Candidate]:
        return _guide(ctx, steps, i, after, 0, failed)

    # which arm takes the group decides which routes (a first guide it cannot route blames
    # "arms": the other arm's take is tried next)
    def decides(after: CableState) -> dict[str, str]:
        return {"arms": f"{after.routing_arm} routes"}

    yield from _chosen(ctx, i, step, state, _stepped(i, taking), then, decides)


def _chosen(
    ctx: PlanningContext,
    i: int,
    step: Skill,
    state: CableState,
    ways: Iterator[tuple[list[Segment], CableState]],
    then: Callable[[CableState], Iterator[Candidate]],
    decides: Callable[[CableState], dict[str, str]],
) -> Iterator[Candidate]:
    """``ways`` of ``steps[i]`` from ``state`` as candidates (narrowed to the IK branches
    that run them, _narrowed); when every one strands an arm, that error."""
    offered, stranded = False, set[str]()
    for segments, after in ways:
        narrowed = _narrowed(ctx, state, segments, after)
        if isinstance(narrowed, str):
            stranded.add(narrowed)
            continue
        offered = True
        segments, after = narrowed
        yield Candidate(
            tuple(segments), then=functools.partial(then, after), decides=decides(after)
        )
    if not offered and stranded:
        with at_step(i):
            raise _stranded(i, step, stranded)


def _stepped(
    i: int, ways: Iterator[tuple[list[Segment], CableState]]
) -> Iterator[tuple[list[Segment], CableState]]:
    """``ways``, their errors those of plan step ``i``."""
    with at_step(i):
        yield from ways


def _guide(
    ctx: PlanningContext,
    steps: Sequence[Skill],
    i: int,
    state: CableState,
    k: int,
    failed: Failed,
) -> Iterator[Candidate]:
    """RouteCable ``steps[i]``: the candidates for its guide ``k``, each a choice of its own
    (a later guide that cannot be routed from where a way left the hands sends the compiler
    back to this guide's next way)."""
    step = steps[i]
    assert isinstance(step, RouteCable)
    last = k + 1 == len(step.guides)
    key = (i, k, state.key())
    with at_step(i):
        if key in failed:  # none of its ways from this state: as found the first time
            if (error := failed[key]) is not None:
                raise error
            return
        # the other hand's releases the compiler could not run from this state (their poses'
        # bytes): every way that begins with one is left out before it is built
        dead: set[bytes] = set()
        ways = _ways(ctx, step, state, k, dead)
        offered, stranded = False, set[str]()
        while True:
            try:
                segments, after = next(ways)
            except StopIteration:
                if offered:
                    return
                why = failed[key] = _stranded(i, step, stranded) if stranded else None
                if why is not None:
                    raise why from None
                return
            except InputError as e:
                if not offered:
                    if k == 0 and e.blames is None:
                        # the first guide, from where the connector was placed: the other
                        # routing arm changes every way of it, another placing by the same
                        # arm few (PlaceConnector decides who routes; the rest are tried after)
                        e.blames = "arms"
                    failed[key] = e
                raise
            narrowed = _narrowed(ctx, state, segments, after)
            if isinstance(narrowed, str):
                stranded.add(narrowed)
                continue
            segments, after = narrowed
            offered = True
            then = (
                functools.partial(_from, ctx, steps, i + 1, after, failed)
                if last
                else functools.partial(_guide, ctx, steps, i, after, k + 1, failed)
            )
            failed_at = functools.partial(_release_failed, segments, dead)
            yield Candidate(tuple(segments), then=then, failed_at=failed_at)


def _release_failed(segments: Sequence[Segment], dead: set[bytes], j: int) -> None:
    """Candidate.failed_at of a guide's way: its first segment, the other hand letting go of
    the last guide, or a segment of the hand swap (cable_swap) could not be compiled."""
    first = segments[0]
    if j == 0 and first.label.endswith(RELEASE) and len(first.paths) == 1:
        dead.add(np.asarray(first.paths[0].poses).tobytes())
    if cable_swap.SWAP in segments[j].label:
        dead.add(cable_swap.key(segments))


def _ways(
    ctx: PlanningContext, step: RouteCable, state: CableState, k: int, dead: Set[bytes]
) -> Iterator[tuple[list[Segment], CableState]]:
    """Guide ``k``'s ways: the routing arm's (_routed), then, after all of them, the other
    arm's once it has taken the cable over (cable_swap, after a routed guide): a plan that
    compiles with the first never reaches the second. When none has a way, the first error
    (it says what blocks the published way)."""
    first: InputError | None = None
    found = False
    for ways in (_routed, _swapped):
        try:
            for way in ways(ctx, step, state, k, dead):
                found = True
                yield way
        except InputError as e:
            first = first or e
    if not found and first is not None:
        raise first


def _routed(
    ctx: PlanningContext,
    step: RouteCable,
    state: CableState,
    k: int,
    dead: Set[bytes],
    shared: Shared | None = None,
) -> Iterator[tuple[list[Segment], CableState]]:
    """The published slide and pivot's ways (RouteCable.ways, ``shared`` its), then laying
    the cable over the guide's top and pushing it in (cable_top, for a guide too close to
    the one before); the first's error when neither has a way."""
    first: InputError | None = None
    try:
        yield from step.ways(ctx, state, k, dead, shared)
    except InputError as e:
        first = e
    try:
        yield from cable_top.top_ways(ctx, step, state, k, dead)
    except InputError:
        if first is not None:
            raise first from None


def _swapped(
    ctx: PlanningContext, step: RouteCable, state: CableState, k: int, dead: Set[bytes]
) -> Iterator[tuple[list[Segment], CableState]]:
    """_routed's ways of the other arm, each after a hand swap (cable_swap.hand_swaps), a
    swap's until the compiler could not run it; none before the first guide (PlaceConnector
    decides who routes it). When the other arm has no way after a swap, the error ends the
    swaps: the guide's ways are screened in full for each, and where the routing hand went
    out of the way changes few of their checks."""
    if k == 0:
        return
    shared: Shared = {}  # the swaps differ in where the hand letting go went
    for swap, swapped in cable_swap.hand_swaps(ctx, step, state, k, dead):
        which = cable_swap.key(swap)
        for segments, after in _routed(ctx, step, swapped, k, dead, shared):
            if which in dead:
                break
            yield [*swap, *segments], after


def _stranded(i: int, step: Skill, arms: set[str]) -> InputError:
    """Every way of ``step`` dropped by _narrowed: which arms it left with no IK branch."""
    which = " or ".join(sorted(arms))
    return InputError.at(
        f"steps[{i}] {step.skill}: every way of doing it leaves an arm ({which}) on no inverse "
        "kinematics branch that follows its Cartesian paths within reach and clear of itself "
        "from where the steps before left it",
        None,
    )


def _narrowed(
    ctx: PlanningContext, state: CableState, segments: Sequence[Segment], after: CableState
) -> tuple[list[Segment], CableState] | str:
    """``segments`` requiring of each arm the IK branches it may be on (Segment.branches), and
    ``after`` (the state they leave from ``state``) with those: the branches of ``state``'s
    on which the arm follows its Cartesian paths in ``segments`` within reach and clear of
    itself (any after a transit of it), and that the skill's checks kept (``after``'s). The
    arm, when one is left with none: no transit before could choose a branch that runs them."""
    from cellengine.execute.following import surviving  # the motion stack: planning only

    branches = dict(state.branches)
    runs: dict[str, list[int]] = {}  # each arm's segments since its last transit in these
    required: list[dict[str, frozenset[int]]] = [{} for _ in segments]

    def close(arm: str) -> None:
        for k in runs.pop(arm, []):
            if arm in branches:
                required[k][arm] = branches[arm]

    for k, segment in enumerate(segments):
        moved = {p.arm for p in segment.paths if p.kind == "transit"}
        for arm, given in segment.branches:  # the skill's own (a release's: _letting_go)
            if arm not in moved:
                branches[arm] = branches.get(arm, ANY_BRANCH) & given
                if not branches[arm]:
                    return arm
        for path in segment.paths:
            if path.kind == "transit":
                close(path.arm)
                branches.pop(path.arm, None)
            else:
                may = branches.get(path.arm, ANY_BRANCH)
                alive, _ = surviving(ctx.cell, ctx.checker, path.arm, path.poses, ctx.home, may)
                if not alive:
                    return path.arm
                branches[path.arm] = frozenset(alive)
            runs.setdefault(path.arm, []).append(k)
    for arm in list(runs):
        kept = branches.get(arm, ANY_BRANCH) & after.branches_of(arm)
        if not kept:
            return arm
        branches[arm] = kept
        close(arm)
    out = [
        replace(s, branches=_joined(s.branches, r)) if r else s
        for s, r in zip(segments, required, strict=True)
    ]
    return out, replace(after, branches=branches)


def _joined(
    given: tuple[tuple[str, frozenset[int]], ...], found: dict[str, frozenset[int]]
) -> tuple[tuple[str, frozenset[int]], ...]:
    """Segment.branches: the skill's and those _narrowed found, each arm on both."""
    out = dict(given)
    for arm, b in found.items():
        out[arm] = out[arm] & b if arm in out else b
    return tuple(sorted(out.items()))


FAMILY = CableFamily()
