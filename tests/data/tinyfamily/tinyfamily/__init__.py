"""A tiny skill family from another package: ``Hover`` takes one arm's fingertip over a
keypoint, pointing down, and back to its rest. It offers the hover heights it is given in
order, so a plan can ask for one the arm cannot reach first: the compiler must then take the
next candidate."""

from __future__ import annotations

import functools
from collections.abc import Iterator, Sequence
from typing import Literal

import numpy as np

from cellengine.context import PlanningContext
from cellengine.errors import Problem, StepError
from cellengine.family import Candidate
from cellengine.geometry import pose
from cellengine.info.units import Length
from cellengine.program import ArmPath, Segment
from cellengine.skill import KeypointRef, Skill


class Hover(Skill):
    skill: Literal["Hover"]
    over: KeypointRef
    heights: tuple[Length, ...] = (0.1,)  # above the keypoint, best first


class TinyFamily:
    name = "tiny"
    skills: tuple[type[Skill], ...] = (Hover,)

    def plan(self, ctx: PlanningContext, steps: Sequence[Skill]) -> Iterator[Candidate]:
        return _ways(ctx, steps, 0)


def _ways(ctx: PlanningContext, steps: Sequence[Skill], i: int) -> Iterator[Candidate]:
    if i == len(steps):
        return
    step = steps[i]
    assert isinstance(step, Hover)
    arm = step.arm if step.arm in ctx.cell.arms else next(iter(ctx.cell.arms))
    if not step.heights:
        raise StepError(Problem(f"steps[{i}] Hover: no heights to try"), i)
    down = np.diag([1.0, -1.0, -1.0])  # the tool's z pointing down
    for h in step.heights:
        T = pose(ctx.world.pose(step.over)[:3, 3] + [0.0, 0.0, h])
        T[:3, :3] = down
        rest = ctx.tcp_home(arm)
        over = Segment(i, f"Hover {step.over}: {h * 1000:g} mm over", (_to(arm, T),))
        back = Segment(i, f"Hover {step.over}: back", (_to(arm, rest),))
        then = functools.partial(_ways, ctx, steps, i + 1) if i + 1 < len(steps) else None
        yield Candidate((over, back), then=then)


def _to(arm: str, T_cell_tcp: np.ndarray) -> ArmPath:
    return ArmPath(arm, "transit", T_cell_tcp[None])


FAMILY = TinyFamily()
