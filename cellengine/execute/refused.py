"""Why a segment cannot run, said in plan terms.

The solving, timing and checking code raises :class:`Refused` with what went wrong in motion
terms ("the left arm's Cartesian path stops at 40 % of its length: waypoint 12: ..."); the
compiler adds which step and which segment, and where the step is in the plan file, and raises
an :class:`~cellengine.errors.InputError` (a plan that cannot run: exit 1, no traceback).
"""

from __future__ import annotations

from pathlib import Path

from cellengine.errors import InputError
from cellengine.info.yamlio import load_yaml
from cellengine.program import Segment


class Refused(Exception):
    """A segment that cannot be compiled; the message says why, without the step."""


class NoMoreChoices(Refused):
    """A choice the compiler asked for (the n-th goal configuration of a transit) does not
    exist: there is nothing more to try at this segment."""


class ChoicesExhausted(InputError):
    """NoMoreChoices in plan terms (only the compiler's search sees it)."""


def step_name(segment: Segment) -> str:
    """How messages name a segment: ``step 3 (RouteCable guide2: lift)``; steps count from 1
    as users read the plan (``Segment.step`` is the 0-based index into ``steps``)."""
    return f"step {segment.step + 1} ({segment.label})"


def in_plan_terms(segment: Segment, why: Refused, plan_file: Path | None = None) -> InputError:
    """The error a user sees: the step and segment, then why; at the step's line in the plan
    file when it is known."""
    message = f"{step_name(segment)}: {why}"
    cls = ChoicesExhausted if isinstance(why, NoMoreChoices) else InputError
    if plan_file is None:
        return cls.at(message, None)
    try:
        line, col = load_yaml(plan_file).where(("steps", segment.step)) or (None, None)
    except InputError:  # the plan file is gone or unreadable: the message alone still helps
        line, col = None, None
    return cls.at(message, plan_file, line, col)
