"""Where a compile stopped, as data: what the report of a failed plan draws and names.

The solving, timing and checking code says where a segment failed in motion terms
(:class:`FailedAt`, on :class:`~cellengine.execute.refused.Refused`): the whole cell's
configuration then, the two objects that collide or come too close, the time, the TCP
positions an arm could not reach. The compiler adds which step and segment, and what it had
compiled before it (:class:`Failure`, on the :class:`~cellengine.errors.StepError` a user
sees), so the report needs no message parsed back.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Literal

from cellengine.arrays import Vec

if TYPE_CHECKING:
    from cellengine.program import Program, Segment

# collision, clearance: a pair too close; unreachable: no IK solution of a pose; limit: a
# joint's position, velocity or acceleration; transit: no free path found; segment: where
# the arms were (where the segment began, unless the raiser knew better): nothing more known
Kind = Literal["collision", "clearance", "unreachable", "limit", "transit", "segment"]


@dataclass(frozen=True)
class FailedAt:
    """Where a segment failed. ``q``: the whole cell's configuration (the cell's joint order)
    to show: the colliding one, the last reached, or the start; ``pair``: the objects (scene
    names, e.g. ``left/tool``, ``routing.guide1``) that collide or come too close; ``time``:
    on the program's time axis, for a timed motion; ``targets``: arm -> TCP position (m, cell
    frame) it could not reach."""

    kind: Kind
    q: Vec | None = None
    pair: tuple[str, str] | None = None
    time: float | None = None
    targets: Mapping[str, Vec] = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True)
class Failure:
    """A plan's compile stopped at ``segment`` (None: a skill refused the step before any
    segment of it), ``at`` (None: not known). ``before``: the program compiled before it, on
    the attempt that got furthest (None: not compiled, see ``ahead``); ``ahead``: the segments
    of the candidates taken before a refused step, not compiled yet (the compiler grows the
    plan's candidates before compiling them)."""

    step: int | None
    segment: Segment | None = None
    at: FailedAt | None = None
    before: Program | None = None
    ahead: tuple[Segment, ...] = ()
