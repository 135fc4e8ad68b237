"""``run --cycles N``: a plan played N times over, as a production cell repeats its cycle.
Only a plan that ends where it starts can be: the arms at the first segment's start and
the grippers holding nothing (``return_home: true`` in the plan ends it at the homes)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from cellengine.errors import InputError, Problem
from cellengine.runner.summary import joint_unit

if TYPE_CHECKING:
    from cellengine.pipeline import Compiled

SAME_PLACE = 1e-6  # rad (m for a prismatic joint): the end this close to the start is it


def check_cycles(compiled: Compiled, cycles: int) -> None:
    """An error (exit 1, at the plan file) unless ``compiled`` can be played ``cycles``
    times in a row: nothing has moved yet."""
    if cycles == 1:
        return
    program, cell = compiled.program, compiled.cell
    plan = str(compiled.loaded.plan.file)
    ends = program.tools_at(program.duration)
    for arm, tool in program.tools.items():
        if ends[arm] != tool:
            raise InputError(
                Problem(
                    f"--cycles {cycles}: the plan ends with the {arm} arm carrying "
                    f"{_tool(ends[arm])}, and starts with it carrying {_tool(tool)}: a cycle "
                    "must end with the tools it starts with (add a ChangeTool step)",
                    plan,
                )
            )
    start, end = program.segments[0].trajectory.q[0], program.segments[-1].trajectory.q[-1]
    for arm, s in cell.slices.items():
        off = np.abs(end[s] - start[s])
        if float(off.max()) > SAME_PLACE:
            j = int(np.argmax(off))
            joint = cell.arms[arm].joint_names[j]
            raise InputError(
                Problem(
                    f"--cycles {cycles}: the plan ends with the {arm} arm "
                    f"{off[j]:.3f} {joint_unit(compiled, joint)} from where it starts (joint "
                    f"'{joint}'): a cycle must "
                    "end where the next one starts; give the plan `return_home: true`",
                    plan,
                )
            )
    holding = {e.event.arm: e.event.holds for e in program.events}
    for arm, held in holding.items():
        if held is not None:
            raise InputError(
                Problem(
                    f"--cycles {cycles}: the plan ends with the {arm} gripper holding "
                    f"'{held}': a cycle must end with nothing held",
                    plan,
                )
            )


def _tool(name: str | None) -> str:
    return f"'{name}'" if name is not None else "no tool"
