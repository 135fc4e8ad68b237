"""Why a segment cannot run, said in plan terms.

The solving, timing and checking code raises :class:`Refused` with what went wrong in motion
terms ("the left arm's Cartesian path stops at 40 % of its length: waypoint 12: ..."); the
compiler adds which step and which segment and raises a :class:`~cellengine.errors.StepError`
(a plan that cannot run: exit 1, no traceback) carrying the step's index; the pipeline puts
it at the step's line in the plan file.
"""

from __future__ import annotations

from cellengine.errors import Problem, StepError
from cellengine.execute.failure import FailedAt, Failure
from cellengine.program import Program, Segment


class Refused(Exception):
    """A segment that cannot be compiled; the message says why, without the step.
    ``configuration``: an arm's own configuration is to blame (a joint limit or jump, its IK
    branch's reach, its links meeting each other): the transit that chose its branch and
    turns, not the path, may be what has to change. ``at``: where, as data (the report
    draws it), when the raiser knows more than the configuration the segment started from."""

    def __init__(
        self, message: str, configuration: bool = False, at: FailedAt | None = None
    ) -> None:
        super().__init__(message)
        self.configuration = configuration
        self.at = at


class NoMoreChoices(Refused):
    """A choice the compiler asked for (the n-th goal configuration of a transit) does not
    exist: there is nothing more to try at this segment."""


class ChoicesExhausted(StepError):
    """NoMoreChoices in plan terms (only the compiler's search sees it)."""


def step_name(segment: Segment) -> str:
    """How messages name a segment: ``step 3 (RouteCable guide2: lift)``; steps count from 1
    as users read the plan (``Segment.step`` is the 0-based index into ``steps``)."""
    return f"step {segment.step + 1} ({segment.label})"


def in_plan_terms(segment: Segment, why: Refused, before: Program | None = None) -> StepError:
    """The error a user sees: the step and segment, then why; carrying the step's index, so
    whoever has the plan puts it at the step's line, and where it failed (``before``: what
    was compiled before it) for the report."""
    cls = ChoicesExhausted if isinstance(why, NoMoreChoices) else StepError
    error = cls(Problem(f"{step_name(segment)}: {why}"), segment.step)
    error.blames = "configuration" if why.configuration else None
    error.failure = Failure(segment.step, segment, why.at, before)
    return error
