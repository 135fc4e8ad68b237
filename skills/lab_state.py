"""What the lab skills hand from one primitive to the next: :class:`LabState`.

Plain data: where every arm's fingertips are, what each gripper holds and how it holds it,
where each container stands, which are still capped, where removed caps are, and the masses
weighed so far. Every pose is in the cell frame (m).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

from cellengine import geometry as g
from cellengine.arrays import Mat
from cellengine.world import World


def _frozen(T: Mat) -> Mat:
    """A read-only rigid copy: every pose here is composed with grasps and their inverses
    at each pick and set-down, so its rotation is kept a rotation (issue 19: the round-off
    tripled at each set-down of one vial until it leant over)."""
    a = g.rigid(T)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Held:
    """A container in a gripper: which, and the grasp as ``T_base_tcp`` (the container's
    base frame to the fingertips), so that where the hand goes the container follows."""

    name: str
    T_base_tcp: Mat


@dataclass(frozen=True, eq=False)
class LabState:
    """``tcp``: T_cell_tcp of every arm. ``held``: arm -> what it holds (absent: nothing).
    ``where``: container -> T_cell_base of each container standing somewhere (a held one is
    not here). ``capped``: containers whose cap is on. ``caps``: removed caps -> T_cell_base.
    ``masses``: container -> mass read by a load cell (kg), once weighed."""

    step: int
    tcp: Mapping[str, Mat]
    held: Mapping[str, Held] = field(default_factory=lambda: MappingProxyType({}))
    where: Mapping[str, Mat] = field(default_factory=lambda: MappingProxyType({}))
    capped: frozenset[str] = frozenset()
    caps: Mapping[str, Mat] = field(default_factory=lambda: MappingProxyType({}))
    masses: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))

    @classmethod
    def start(cls, world: World, tcp: Mapping[str, Mat]) -> LabState:
        """Every container where objects.yaml stands it, capped if it has a cap."""
        where = {
            name: _frozen(world.standing(c))
            for name, c in world.objects.containers.items()
            if c.at is not None
        }
        capped = frozenset(n for n, c in world.objects.containers.items() if c.cap is not None)
        return cls(
            0,
            MappingProxyType({a: _frozen(T) for a, T in tcp.items()}),
            where=MappingProxyType(where),
            capped=capped,
        )

    def holder(self, name: str) -> str | None:
        """The arm holding container ``name``, if one does."""
        return next((arm for arm, h in self.held.items() if h.name == name), None)

    def moved(self, arm: str, T_cell_tcp: Mat) -> LabState:
        return replace(self, tcp=MappingProxyType({**self.tcp, arm: _frozen(T_cell_tcp)}))

    def grasped(self, arm: str, name: str) -> LabState:
        """``arm`` closes on container ``name`` where it stands."""
        T_base_tcp = g.inverse(self.where[name]) @ self.tcp[arm]
        where = {k: v for k, v in self.where.items() if k != name}
        held = {**self.held, arm: Held(name, _frozen(T_base_tcp))}
        return replace(self, held=MappingProxyType(held), where=MappingProxyType(where))

    def released(self, arm: str) -> LabState:
        """``arm`` opens: what it held stands where the hand put it."""
        h = self.held[arm]
        T_cell_base = self.tcp[arm] @ g.inverse(h.T_base_tcp)
        held = {k: v for k, v in self.held.items() if k != arm}
        where = {**self.where, h.name: _frozen(T_cell_base)}
        return replace(self, held=MappingProxyType(held), where=MappingProxyType(where))

    def uncapped(self, name: str, T_cell_cap: Mat) -> LabState:
        caps = {**self.caps, name: _frozen(T_cell_cap)}
        return replace(self, capped=self.capped - {name}, caps=MappingProxyType(caps))

    def weighed(self, name: str, mass: float) -> LabState:
        return replace(self, masses=MappingProxyType({**self.masses, name: mass}))

    def base_of(self, name: str) -> Mat:
        """T_cell_base of container ``name``, standing or held."""
        if name in self.where:
            return self.where[name]
        arm = self.holder(name)
        if arm is None:
            raise KeyError(f"container '{name}' is nowhere: it has no 'at' in objects.yaml")
        out: Mat = self.tcp[arm] @ g.inverse(self.held[arm].T_base_tcp)
        return out
