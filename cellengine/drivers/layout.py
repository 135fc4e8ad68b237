"""Which joints belong to which arm, in the cell's joint order, and each arm's tool.

Drivers see joints by name only (no kinematic model): the caller gives each robot's joint
names, e.g. ``{name: arm.joint_names for name, arm in cell_model.arms.items()}``; the cell's
q is the arms' joints one arm after the other, in the cell file's robot order.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

from cellengine.errors import known
from cellengine.info.cell import Cell, Tool


@dataclass(frozen=True)
class CellLayout:
    joint_names: tuple[str, ...]  # the cell's q, arm after arm
    slices: Mapping[str, slice]  # each arm's entries of q
    tools: Mapping[str, Tool | None]  # each arm's tool (None: no tool)

    @property
    def arms(self) -> tuple[str, ...]:
        return tuple(self.slices)

    def arm_of(self, joint: int) -> str:
        """The arm that joint index ``joint`` of q belongs to."""
        for arm, s in self.slices.items():
            if s.start <= joint < s.stop:
                return arm
        raise IndexError(f"joint index {joint} is outside q ({len(self.joint_names)} joints)")

    def unknown_arm(self, arm: str) -> str | None:
        """Why ``arm`` is not an arm of the cell, or None if it is."""
        return None if arm in self.slices else f"unknown arm '{arm}'" + known(self.slices)

    @staticmethod
    def of(cell: Cell, joints: Mapping[str, Sequence[str]]) -> CellLayout:
        """The layout of ``cell`` with each robot's joint names; every robot of the cell
        needs its joints, in cell order, and no others."""
        if set(joints) != set(cell.robots):
            raise ValueError(
                f"joints are given for {sorted(joints)}; the cell's robots are "
                f"{sorted(cell.robots)}"
            )
        names: list[str] = []
        slices: dict[str, slice] = {}
        tools: dict[str, Tool | None] = {}
        for arm, robot in cell.robots.items():
            own = tuple(joints[arm])
            if not own:
                raise ValueError(f"arm '{arm}' has no joints")
            slices[arm] = slice(len(names), len(names) + len(own))
            names.extend(own)
            tools[arm] = cell.tools.get(robot.tool) if robot.tool is not None else None
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"joint names repeat: {', '.join(dup)}")
        return CellLayout(tuple(names), MappingProxyType(slices), MappingProxyType(tools))
