"""Compiling a skill family's candidates (:mod:`cellengine.family`).

The first candidate at every choice is taken and all their segments are compiled in one go
(:func:`~cellengine.execute.search.add_all`: each transit looks ahead at the segments after
it), each choice's candidate taken when a segment past those taken is asked for
(:mod:`~cellengine.execute.growing`).
When that fails, the choice that produced the failing segment is asked for its next candidate,
then the choices before it; what is compiled before that choice is kept (the compiler is
restored to where that choice's segments began) and compiling goes on with the new
candidates. A family that cannot plan a choice at all (its generator raises) sends the search
to the choice before. An error that blames something a choice decided (``InputError.blames``,
``Candidate.decides``) sends it straight back to the latest choice that decided it, to its
next candidate that decides it otherwise: the choices between could not change it. A
candidate whose segments begin as any failed candidate's of its choice did, up to the one
that failed, is passed over (no transit among them: compiled from the same place, they fail
the same way; ways that differ only after a shared first segment come in any order).
An error that blames an arm's own configuration (a joint limit, its IK branch, its links
meeting) after the search went back sends it first to compiling the candidates taken again
from the start, once: a transit that chose the arm's branch and turns looked ahead at the
candidates taken then, and looks ahead at these. ``MAX_TRIES`` candidates taken in all
(a compile again counts as one); then the error of the attempt that got furthest is raised
(the first of those: an error that a later attempt got past is not what stops the plan):
with one candidate per choice, exactly the error of compiling the first candidates.

Deterministic: candidates are tried in the order the family offers them.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING

import numpy as np

from cellengine.errors import InputError
from cellengine.execute.failure import Failure
from cellengine.execute.growing import Choice, Growing, NoCandidate, Taken
from cellengine.execute.search import add_all
from cellengine.program import Segment

if TYPE_CHECKING:
    from cellengine.execute.compile import Compiler, Mark
    from cellengine.family import Candidate

MAX_TRIES = 32  # candidates taken after the first ones, per compile: a failing plan is
# refused within minutes (bench/bench_boards.py measures it). 16 ran out on boards whose
# previous guide's ways each failed at once at the next guide (board 93 needs 23)


def compile_candidates(
    compiler: Compiler,
    first: Iterator[Candidate],
    before_each: Callable[[Segment], None] | None = None,
) -> list[Candidate]:
    """Compile the candidates into ``compiler`` (see the module notes); the candidates taken,
    in order. The furthest error when no combination within ``MAX_TRIES`` gets through."""
    tree = Taken([], first)
    chosen = tree.chosen
    marks: dict[int, Mark] = {0: compiler.mark()}  # where each choice's segments begin
    start = 0  # the first choice whose segments are not compiled; the compiler is at its mark
    # the error of the attempt that got furthest (the first of those), and how far: (the
    # choice, the place in it) of the segment it stopped at
    reported: tuple[tuple[int, int], InputError] | None = None
    ahead: tuple[Segment, ...] = ()  # a refused choice's: the segments of those before it
    recompiled: set[tuple[int, ...]] = set()  # the combinations compiled again from the start
    for _ in range(MAX_TRIES + 1):
        # the choice of the segment being compiled; the choice, and the place in it, of the
        # furthest segment compiled (where the error the compiler gives arose)
        current = [len(chosen) - 1, -1, -1]
        try:
            _compile_from(compiler, tree, start, marks, before_each, current)
            return [c.taken for c in chosen]
        except NoCandidate as e:  # the choice after the last one taken offered nothing
            if e.error is not None and (reported is None or (len(chosen), -1) > reported[0]):
                reported = (len(chosen), -1), e.error
                ahead = tuple(s for c in chosen for s in c.taken.segments)
            failed, blames = len(chosen), e.error.blames if e.error is not None else None
        except InputError as e:
            # the choice of the furthest segment compiled: going back to earlier transits
            # (search.add_all) ends with the error of the attempt that got furthest
            failed, blames = (current[1] if current[1] >= 0 else current[0]), e.blames
            if reported is None or (failed, current[2]) > reported[0]:
                reported = (failed, current[2]), e
            combination = tuple(id(c.taken) for c in chosen)
            if blames == "configuration" and start > 0 and combination not in recompiled:
                # the transit that chose the arm's branch and turns was compiled looking
                # ahead at other candidates: compile these again from the start, each
                # transit looking ahead at them (what failed from elsewhere may not fail)
                recompiled.add(combination)
                for choice in chosen:
                    choice.failed.clear()
                marks = {0: marks[0]}
                start = 0
                compiler.restore(marks[0])
                continue
            ran = _prefix(chosen[failed].taken.segments, current[2])
            if ran is not None:
                chosen[failed].failed.add(ran)
            failed_at = chosen[failed].taken.failed_at
            if failed_at is not None and current[2] >= 0:
                failed_at(current[2])  # so the family leaves out what would fail there too
        k = _jump(chosen, failed, blames) if blames is not None else None
        k = k if k is not None else _next_candidate(chosen, failed)
        if k is None:
            break
        for j in [j for j in marks if j > k]:
            del marks[j]  # compiled with choices now dropped
        start = max(marks)
        compiler.restore(marks[start])
        then = chosen[k].taken.then
        tree.pending = then() if then is not None else None
    if reported is None:  # a family that offered no candidate at all
        raise InputError.at("the skill family offered no way to do the plan", None)
    error = reported[1]
    if error.failure is None:  # the family refused a choice: nothing of it was compiled
        error.failure = Failure(getattr(error, "step", None), ahead=ahead)
    raise error


def _compile_from(
    compiler: Compiler,
    tree: Taken,
    start: int,
    marks: dict[int, Mark],
    before_each: Callable[[Segment], None] | None,
    current: list[int],
) -> None:
    """Compile the segments of choices ``start`` on (the next choices' candidates taken as
    their segments are asked for: growing.py), marking where each choice begins;
    ``current``: the choice whose segment is being compiled, then the choice of the furthest
    segment compiled and its place in that choice's segments (a failure blames that choice:
    the guides of one RouteCable are choices of one step)."""
    segments = Growing(tree, start)
    furthest = -1

    def before(segment: Segment) -> None:
        nonlocal furthest
        at, current[0], j = segments.owner[id(segment)]
        # add_all came back to this segment: the marks of the choices after it were taken on
        # an attempt it gave up (the compiler can only be restored to a mark behind it)
        for stale in [m for m in marks if m > current[0]]:
            del marks[stale]
        k = segments.begins.get(id(segment))
        if k is not None:
            marks[k] = compiler.mark()
        if at > furthest:
            furthest, current[1], current[2] = at, current[0], j
        if before_each is not None:
            before_each(segment)

    current[0] = start
    add_all(compiler, segments, before)


def _jump(chosen: list[Choice], failed: int, blames: str) -> int | None:
    """Take, at the latest choice up to ``failed`` that decided ``blames`` and has a next
    candidate that decides it otherwise, that candidate; the choices after it are dropped.
    The choice changed, or None (nothing decided it, or no candidate decides it otherwise:
    the search then goes on as without the blame)."""
    for k in range(min(failed, len(chosen) - 1), -1, -1):
        was = chosen[k].taken.decides.get(blames)
        if was is None:
            continue
        passed: list[Candidate] = []  # deciding it the same: still there for the plain search
        while True:
            try:
                taken = next(chosen[k].options)
            except (StopIteration, InputError):
                chosen[k].options = itertools.chain(passed, chosen[k].options)
                break  # an earlier choice may decide it otherwise
            if taken.decides.get(blames) != was:
                del chosen[k + 1 :]
                chosen[k].taken = taken
                chosen[k].options = itertools.chain(passed, chosen[k].options)
                return k
            passed.append(taken)
    return None


def _next_candidate(chosen: list[Choice], failed: int) -> int | None:
    """Take the next candidate at choice ``failed`` or, when it has none, at the choices
    before it; the choices after it are dropped. A candidate whose segments begin as a failed
    one's of its choice (``Choice.failed``) is passed over: compiled from the same place,
    they fail the same way. The choice changed, or None."""
    k = min(failed, len(chosen) - 1)
    del chosen[k + 1 :]
    while k >= 0:
        try:
            taken = next(chosen[k].options)
            while _failed_before(chosen[k], taken):
                taken = next(chosen[k].options)
            chosen[k].taken = taken
            return k
        except StopIteration:
            pass
        except InputError:
            pass  # the family could not plan another: as if it had none
        del chosen[k:]
        k -= 1
    return None


def _failed_before(choice: Choice, taken: Candidate) -> bool:
    """Whether ``taken`` begins as a candidate that failed at ``choice`` did."""
    return any(_prefix(taken.segments, len(ran) - 1) == ran for ran in choice.failed)


def _prefix(segments: tuple[Segment, ...], last: int) -> tuple[object, ...] | None:
    """What ``segments[: last + 1]`` ask of the compiler, comparable with ==; None when there
    is no such segment or one of them has a transit (a transit looks ahead at the segments
    after it: the same transit before other segments may be compiled otherwise)."""
    if last < 0 or last >= len(segments):
        return None
    head = segments[: last + 1]
    if any(p.kind == "transit" for s in head for p in s.paths):
        return None
    return tuple(
        (
            s.label,
            tuple((p.arm, p.kind, np.asarray(p.poses).tobytes()) for p in s.paths),
            s.before,
            s.after,
            s.closed_chain,
            s.keep_distance,
            s.contacts,
            s.near,
            s.branches,
            s.paired,
        )
        for s in head
    )
