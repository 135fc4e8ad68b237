"""The cable-routing skills as a family (:mod:`cellengine.family`): PickCable,
PlaceConnector and RouteCable chained through one :class:`CableState` from the arms' homes,
each step's ways offered to the compiler best first, and the cable released at the end."""

from __future__ import annotations

import functools
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

from cellengine.family import Candidate
from cellengine.skill import Skill
from cellengine.skills.cable import (
    PickCable,
    PlaceConnector,
    RouteCable,
    release_and_retract,
    step_ways,
)
from cellengine.skills.cable_state import CableState

if TYPE_CHECKING:
    from cellengine.context import PlanningContext


class CableFamily:
    name = "cable"
    skills: tuple[type[Skill], ...] = (PickCable, PlaceConnector, RouteCable)

    def plan(self, ctx: PlanningContext, steps: Sequence[Skill]) -> Iterator[Candidate]:
        return _from(ctx, steps, 0, CableState.at_home(ctx))


def _from(
    ctx: PlanningContext, steps: Sequence[Skill], i: int, state: CableState
) -> Iterator[Candidate]:
    """The candidates for ``steps[i]`` from ``state``; after the last step, the release."""
    if i == len(steps):
        segments, _ = release_and_retract(state)
        yield Candidate(tuple(segments))
        return
    for segments, after in step_ways(ctx, steps, i, state):
        yield Candidate(tuple(segments), then=functools.partial(_from, ctx, steps, i + 1, after))


FAMILY = CableFamily()
