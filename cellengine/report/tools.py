"""The tools report.html draws in a cell with a tool changer: every tool, on the arm that
carries it or seated in its slot, sample by sample, and which tool each arm carries when.

The arms' models hold the tools they start with; a tool change moves a tool from an arm to
its slot and another from its slot to the arm, so in such a cell the tools are drawn from
cell.yaml on their own (:func:`tool_links`) and the arms' own tool objects are left out.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from cellengine.arrays import Mat, Vec
from cellengine.info.cell import FINGER_NAMES
from cellengine.motion.robot import CellModel, mesh_reader
from cellengine.motion.tool import Solid, fingers_of, tool_solids
from cellengine.program import Program
from cellengine.report.objects import frame_poses

PREFIX = "tools"  # a drawn tool's name: tools/<tool>/tool[/<part>]


def changes_tools(world_tools: Mapping[str, Any]) -> bool:
    """Whether the cell has a tool changer (any tool with a slot)."""
    return any(t.slot is not None for t in world_tools.values())


def tool_timeline(program: Program) -> dict[str, Any]:
    """The tool each arm carries at the start, and every change (time, arm, tool, was)."""
    return {
        "start": dict(program.tools),
        "changes": [
            {"time": c.time, "arm": c.arm, "tool": c.tool, "was": c.was} for c in program.changes
        ],
    }


def tool_links(
    program: Program, cell: CellModel, world: Any, Q: Vec, times: Vec
) -> list[tuple[str, Any, Mat]]:
    """Each solid of every tool that has a slot or that an arm carries: (name, coal shape,
    placements (S, 4, 4) in the cell frame), on its arm's flange while carried (fingers at
    the opening of the arm's last jaw mode since it took the tool), else in its slot."""
    flanges = frame_poses(cell, Q, cell.tool0)
    carried = _carried(program, times)
    modes = _modes(program, times)
    names = sorted({t for row in carried for t in row.values() if t is not None})
    names += sorted(n for n, t in world.cell.tools.items() if t.slot is not None and n not in names)
    out: list[tuple[str, Any, Mat]] = []
    for name in names:
        tool = world.cell.tools[name]
        T_flange_tcp = tool.tcp.matrix()
        solids = tool_solids(
            tool, T_flange_tcp, mesh_reader(world.cell_file, name, world.cell.units)
        )
        fingers = fingers_of(tool, T_flange_tcp)
        T_slot = world.slot(name) if tool.slot is not None else None
        for solid in solids:
            M = np.empty((len(times), 4, 4))
            for s in range(len(times)):
                arm = next((a for a, t in carried[s].items() if t == name), None)
                T_base = flanges[arm][s] if arm is not None else T_slot
                T_solid = _finger(solid, fingers, modes[s].get(arm) if arm else None)
                M[s] = (T_base if T_base is not None else np.eye(4)) @ T_solid
            out.append((f"{PREFIX}/{name}/{solid.name}", solid.shape, M))
    return out


def _finger(solid: Solid, fingers: Any, mode: str | None) -> Mat:
    """The solid in the flange frame; a finger at the opening of ``mode`` (the widest when
    no mode is known)."""
    side = [f"tool/{n}" for n in FINGER_NAMES]
    if fingers is None or solid.name not in side:
        return np.asarray(solid.T_flange_solid, dtype=float)
    opening = fingers.opening(mode) if mode is not None else fingers.widest
    return np.asarray(fingers.placements(opening)[side.index(solid.name)], dtype=float)


def _carried(program: Program, times: Vec) -> list[dict[str, str | None]]:
    return [program.tools_at(float(t)) for t in times]


def _modes(program: Program, times: Vec) -> list[dict[str, str]]:
    """Per sample, each arm's last jaw mode since its last tool change."""
    events = sorted(
        [(e.time, 0, e.event.arm, e.event.mode) for e in program.events]
        + [(c.time, 1, c.arm, None) for c in program.changes]
    )
    out: list[dict[str, str]] = []
    state: dict[str, str] = {}
    k = 0
    for t in times:
        while k < len(events) and events[k][0] <= t + 1e-9:
            _, _, arm, mode = events[k]
            if mode is None:
                state.pop(arm, None)
            else:
                state[arm] = mode
            k += 1
        out.append(dict(state))
    return out
