"""Compiling a whole plan: each segment in turn, and back to an earlier transit when a later
segment cannot run from where it left the arms.

A transit can reach its goal pose in several configurations (IK branches), and which one it
takes decides what comes after: the next Cartesian path of the same arm is looked at when the
goal is chosen (solve.transit), but a later move of the *other* arm can run into this arm's
elbow or wrist as well. When a segment fails, the compiler goes back to the latest transit
before it (within ``LOOKBACK`` segments), takes that transit's next goal configuration, and
compiles on from there; a transit out of choices sends it further back. ``BUDGET`` retries in
all; then the error of the attempt that got furthest is raised (the first of those, on a tie):
it names the step and segment where the plan really gets stuck.

Deterministic: the choices are tried in one fixed order.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from cellengine.errors import InputError
from cellengine.execute.refused import ChoicesExhausted
from cellengine.program import Segment

if TYPE_CHECKING:
    from cellengine.execute.compile import Compiler

LOOKBACK = 12  # segments: how far back a failure may send the compiler
BUDGET = 12  # retries (re-chosen transits) per plan: a few seconds at most on a plan that fails


def add_all(
    compiler: Compiler,
    segments: Sequence[Segment],
    before_each: Callable[[Segment], None] | None = None,
) -> None:
    """Add every segment to ``compiler``, retrying earlier transits' goal configurations as
    described above; InputError when no retry within the budget gets through.
    ``before_each`` is called with each segment before it is compiled (again when the search
    comes back to it): for a progress display."""
    choices: defaultdict[int, int] = defaultdict(int)  # per segment: its transit's goal
    marks = {}
    best: tuple[int, InputError] | None = None
    retries = 0
    i = 0
    while _within(segments, i):
        marks[i] = compiler.mark()
        if before_each is not None:
            before_each(segments[i])
        try:
            compiler.add(segments[i], segments[i + 1 :], choices[i])
            i += 1
            continue
        except InputError as e:
            exhausted = isinstance(e, ChoicesExhausted)
            if not exhausted and (best is None or i > best[0]):
                best = (i, e)
            failed = e
        back = _transit_before(segments, i, include=not exhausted)
        if back is None or retries >= BUDGET:
            raise best[1] if best is not None else failed
        retries += 1
        for k in range(back + 1, i + 1):
            choices[k] = 0
        choices[back] += 1
        compiler.restore(marks[back])
        i = back


def _within(segments: Sequence[Segment], i: int) -> bool:
    """Whether there is an i-th segment, asked without len(): a sequence that takes its
    candidates as they are asked for (execute.growing) takes no more than it must."""
    try:
        segments[i]
    except IndexError:
        return False
    return True


def _transit_before(segments: Sequence[Segment], i: int, *, include: bool) -> int | None:
    """The latest segment at or before i (before i when not ``include``), within LOOKBACK,
    that has a transit."""
    last = i if include else i - 1
    for k in range(last, max(-1, i - LOOKBACK - 1), -1):
        if any(p.kind == "transit" for p in segments[k].paths):
            return k
    return None
