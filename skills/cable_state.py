"""What the cable skills hand from one step to the next: :class:`CableState`.

A cable skill's ``plan(ctx, state)`` starts where the previous step left the arms and the
cable, and returns the state after its last segment. The state is plain data (poses, names,
lengths); nothing in it talks to a driver.

Lengths along the cable (``s``) are in metres from the connector's rear face, the point where
the cable leaves the connector (objects.yaml: a cable's ``length`` runs from there to the free
end); a negative ``s`` is on the connector itself (its centre is at ``-connector.length / 2``).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from cellengine.arrays import Mat
from cellengine.program import GripperEvent, ToolChange
from cellengine.skills.cable_geometry import LEAN, turn_about_vertical

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

Point = tuple[float, float, float]
ANY_BRANCH = frozenset(range(8))  # a UR arm's closed-form IK branches


@dataclass(frozen=True)
class Hold:
    """What one gripper holds: ``cable`` at ``s`` (m from the connector's rear face)."""

    cable: str
    s: float


@dataclass(frozen=True, eq=False)
class Placed:
    """A connector PlaceConnector placed, for the groups of its harness routed from it
    later: its guide, the point its cable leaves it (its rear face), the hold behind it
    that the placing ended with (its arm, the routing hand's TCP, the hold's ``s``, the
    cable from the rear face to the fingertips) and where the other arm then stood."""

    guide: str
    rear: Point
    arm: str
    T_hold: Mat
    s_hold: float
    pull_distance: float
    T_other: Mat  # the other arm's TCP as the placing left it

    def key(self) -> tuple[object, ...]:
        return (
            self.guide,
            self.rear,
            self.arm,
            np.round(self.T_hold, 9).tobytes(),
            round(self.s_hold, 9),
            round(self.pull_distance, 9),
            np.round(self.T_other, 9).tobytes(),
        )


def _frozen(T: NDArray[np.float64]) -> Mat:
    a = np.array(T, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class CableState:
    """The cell as the cable skills see it after the last planned segment.

    ``tcp``: T_cell_tcp of every arm. ``mode``: every gripper's jaw mode (a name in its tool's
    ``jaw`` table; None until a skill sets one). ``held``: what each gripper holds (an arm
    absent holds nothing). ``step``: the plan step index the next ``plan()`` writes into its
    segments. ``cable``: the cable being worked on. ``connector_arm``: the arm that holds, or
    will hold, the connector end (PlaceConnector's arm); ``routing_arm`` the other one, once
    the connector is placed. ``place_guide``: the connector guide of the coming PlaceConnector,
    so PickCable can prepare the grasp that guide needs (the published PickCable already
    slides for "the connector that will be inserted in the following operation").
    ``guides``: the guides the cable passes through, in order, the connector guide first.
    ``route``: the points (cell frame, m) the laid cable runs through, from the connector's
    rear face to the last guide's slot. ``pull_distance``: the cable (m) between the last of
    those points and the routing fingertips, which the routing hand pulls through the next
    guide; set by PlaceConnector, updated by every routed guide (published Algorithm 1).
    ``lean``: the tip the hands keep along the cable (cable_geometry.LEAN unless PickCable
    took another way).
    """

    tcp: Mapping[str, Mat]
    mode: Mapping[str, str | None]
    held: Mapping[str, Hold] = field(default_factory=lambda: MappingProxyType({}))
    step: int = 0
    cable: str | None = None
    connector_arm: str | None = None
    routing_arm: str | None = None
    place_guide: str | None = None
    guides: tuple[str, ...] = ()
    route: tuple[Point, ...] = ()
    pull_distance: float = 0.0
    # how far both hands tip their flanges apart along the cable while they hold it (the
    # connector hand keeps it until the connector is placed): PickCable's way sets it
    lean: float = LEAN
    # how far each TCP has turned about the vertical since home (rad, signed, summed along
    # every path): the wrist's winding, which nearer_turn keeps within WIND_LIMIT
    wound: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))
    # the IK branches (ArmIK.by_branch rows) each arm may still be on: those that followed
    # every pose the skills screened since the arm's last transit; an arm absent, any
    branches: Mapping[str, frozenset[int]] = field(default_factory=lambda: MappingProxyType({}))
    # harnesses (and cables) by name -> where their connector was placed (cable_group)
    placed: Mapping[str, Placed] = field(default_factory=lambda: MappingProxyType({}))
    # the single cables whose routing has begun (a harness's groups are taken one by one)
    routed: frozenset[str] = frozenset()
    # the tool each arm carries (None: a bare flange); ``tcp`` is that tool's TCP
    tools: Mapping[str, str | None] = field(default_factory=lambda: MappingProxyType({}))
    # harnesses -> their cables laid aside in a separation guide (cable_aside.Aside)
    aside: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "tcp", MappingProxyType({a: _frozen(T) for a, T in self.tcp.items()})
        )
        object.__setattr__(self, "mode", MappingProxyType(dict(self.mode)))
        object.__setattr__(self, "held", MappingProxyType(dict(self.held)))
        object.__setattr__(self, "wound", MappingProxyType(dict(self.wound)))
        object.__setattr__(self, "branches", MappingProxyType(dict(self.branches)))
        object.__setattr__(self, "placed", MappingProxyType(dict(self.placed)))
        object.__setattr__(self, "tools", MappingProxyType(dict(self.tools)))
        object.__setattr__(self, "aside", MappingProxyType(dict(self.aside)))

    @classmethod
    def at_home(cls, ctx: PlanningContext) -> CableState:
        """Every arm's TCP at the cell's home configuration, grippers in no known mode,
        nothing held."""
        tcp = {name: ctx.tcp_home(name) for name in ctx.cell.arms}
        return cls(tcp=tcp, mode={name: None for name in tcp}, tools=ctx.world.tools)

    @property
    def arms(self) -> tuple[str, ...]:
        return tuple(self.tcp)

    def moved(self, arm: str, T_cell_tcp: Mat) -> CableState:
        return self.moved_along(arm, np.asarray(T_cell_tcp)[None])

    def moved_along(self, arm: str, poses: NDArray[np.float64]) -> CableState:
        """The arm's TCP at the last of ``poses`` (n, 4, 4), its turn about the vertical
        summed pose to pose from where it is (each step the shorter way round)."""
        turn, T = 0.0, self.tcp[arm]
        for T_next in poses:
            turn += turn_about_vertical(T, T_next)
            T = T_next
        wound = {**self.wound, arm: self.wound.get(arm, 0.0) + turn}
        return replace(self, tcp={**self.tcp, arm: poses[-1]}, wound=wound)

    def key(self) -> tuple[object, ...]:
        """The state as a hashable value, poses to 1e-9 m (a skill given states with equal
        keys does the same)."""
        return (
            tuple((a, np.round(T, 9).tobytes()) for a, T in sorted(self.tcp.items())),
            tuple((a, m) for a, m in sorted(self.mode.items())),
            tuple(sorted(self.held.items())),
            (self.step, self.cable, self.connector_arm, self.routing_arm, self.place_guide),
            (self.guides, self.route, round(self.pull_distance, 9), round(self.lean, 9)),
            tuple((a, round(w, 9)) for a, w in sorted(self.wound.items())),
            tuple((a, tuple(sorted(b))) for a, b in sorted(self.branches.items())),
            tuple((n, p.key()) for n, p in sorted(self.placed.items())),
            tuple(sorted(self.routed)),
            tuple(sorted(self.tools.items())),
            tuple(sorted(self.aside.items())),
        )

    def branches_of(self, arm: str) -> frozenset[int]:
        return self.branches.get(arm, ANY_BRANCH)

    def transited(self, *arms: str) -> CableState:
        """After a transit of ``arms``: each may reach its goal on any branch."""
        return replace(self, branches={a: b for a, b in self.branches.items() if a not in arms})

    def gripped(self, event: GripperEvent) -> CableState:
        """After a gripper event: its mode; nothing held when it opens (an event that holds
        something keeps the arm's current :class:`Hold`, which the skill sets with ``hold``)."""
        held = dict(self.held)
        if event.holds is None:
            held.pop(event.arm, None)
        return replace(self, mode={**self.mode, event.arm: event.mode}, held=held)

    def changed(self, change: ToolChange) -> CableState:
        """After a tool change: the arm carries the new tool (its gripper in no known mode,
        its TCP where the skill says: a tool's TCP is not the flange's)."""
        return replace(
            self,
            tools={**self.tools, change.arm: change.tool},
            mode={**self.mode, change.arm: None},
        )

    def hold(self, arm: str, cable: str, s: float) -> CableState:
        return replace(self, held={**self.held, arm: Hold(cable, s)})

    def route_length(self) -> float:
        """Length (m) of the laid cable from the connector's rear face to the last route point."""
        if len(self.route) < 2:
            return 0.0
        p = np.asarray(self.route, dtype=float)
        return float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
