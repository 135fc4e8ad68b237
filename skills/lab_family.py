"""The lab skills as a family (:mod:`cellengine.family`): the allocator decides which robots
do each step and in what order, and the mission's actions become segments. One candidate:
the mission of least travel; report.json gets the mission with each part's actual times."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import TYPE_CHECKING, Any

from cellengine.family import Candidate
from cellengine.program import Program
from cellengine.skill import Skill
from cellengine.skills.lab import BimanualCarry, Handover, Pick, Place, Pour, Unscrew, Weigh

if TYPE_CHECKING:
    from cellengine.context import PlanningContext


class LabFamily:
    name = "lab"
    skills: tuple[type[Skill], ...] = (Pick, Place, Handover, Unscrew, Weigh, Pour, BimanualCarry)

    def plan(self, ctx: PlanningContext, steps: Sequence[Skill]) -> Iterator[Candidate]:
        # the allocator and the motion stack: when a plan is compiled, not when parsed
        from cellengine.skills.lab_plan import mission_json, plan_lab_steps

        overlap = ctx.execution != "sequential"
        lab = plan_lab_steps(ctx, steps, overlap)

        def report(program: Program) -> Mapping[str, Any]:
            if program.streams:  # the robots at once: each segment where it was placed
                spans = [(s.part, s.start, s.end) for s in program.streams]
            else:
                spans = [
                    (s.segment.facts.get("mission"), s.trajectory.start_time, s.trajectory.end_time)
                    for s in program.segments
                ]
            return {"mission": mission_json(lab.mission, spans)}

        rules = lab.overlap(ctx.world) if overlap else None
        yield Candidate(tuple(lab.segments), report=report, overlap=rules)


FAMILY = LabFamily()
