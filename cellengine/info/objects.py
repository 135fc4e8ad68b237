"""objects.yaml (DESIGN 3.3): cables, harnesses (cellengine.info.harness) and containers."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, ValidationInfo, field_validator, model_validator

from cellengine.info.camera import MarkerId
from cellengine.info.cell import Name
from cellengine.info.connector import Connector
from cellengine.info.harness import Harness, HarnessCable
from cellengine.info.pose import Pose
from cellengine.info.units import Frozen, Length, Mass, Number, Units


class Cable(Frozen):
    length: Length = Field(gt=0)
    diameter: Length = Field(gt=0)
    color: str | None = None
    connector: Connector | None = None
    mass: Mass | None = Field(None, ge=0)


class Cap(Frozen):
    kind: Literal["screw"]
    pitch: Length = Field(gt=0)
    turns: Number = Field(gt=0)


class Container(Frozen):
    kind: Literal["vial", "beaker", "bottle", "box"]
    diameter: Length | None = Field(None, gt=0)
    size: tuple[Length, Length, Length] | None = None  # boxes: x, y, z
    height: Length | None = Field(None, gt=0)
    mass: Mass | None = Field(None, ge=0)
    cap: Cap | None = None
    # where it stands at the start, the centre of its base, z up: a keypoint
    # (platform.element[.keypoint]) or a pose in the cell frame (`cellengine locate` writes
    # one where it finds a container away from every keypoint)
    at: str | Pose | None = None
    # the ArUco marker on its top (cell.yaml's camera dictionary)
    marker: MarkerId | None = None

    @model_validator(mode="after")
    def _sized(self) -> Container:
        """A box by its size, anything else by its diameter and height: each given for its
        kind (the skills need them) and nothing given that its kind does not use."""
        uses = ("size",) if self.kind == "box" else ("diameter", "height")
        missing = [k for k in uses if getattr(self, k) is None]
        unused = [k for k in ("size", "diameter", "height") if k not in uses and getattr(self, k)]
        sized = f"a {self.kind} is sized by {' and '.join(uses)}"
        if missing:
            raise ValueError(f"{sized}: give {' and '.join(missing)}")
        if unused:
            raise ValueError(f"{sized}: remove {' and '.join(unused)}")
        if self.size is not None and min(self.size) <= 0:
            raise ValueError("box sizes must be greater than 0")
        return self

    @property
    def full_height(self) -> float | None:
        """How tall it stands: a box's size in z, else its height (None: not given)."""
        return self.size[2] if self.size is not None else self.height


def bundle(harness: Harness, cables: tuple[str, ...]) -> Cable:
    """``cables`` of ``harness`` bundled, as one cable: as thick as the bundle, as long as
    its shortest cable, on the harness's connector (lengths already in metres)."""
    masses = [harness.cables[c].mass for c in cables]
    return Cable.model_construct(
        length=min(harness.cables[c].length for c in cables),
        diameter=harness.bundle_diameter(cables),
        color=harness.color,
        connector=harness.connector,
        mass=None if None in masses else sum(m for m in masses if m is not None),
    )


class Objects(Frozen):
    units: Units = Units()
    cables: dict[Name, Cable] = {}
    harnesses: dict[Name, Harness] = {}
    containers: dict[Name, Container] = {}

    def names(self) -> list[str]:
        return [*self.cables, *self.harnesses, *self.containers]

    def cable_names(self) -> list[str]:
        """What a cable skill may pick, place and route: cables, whole harnesses, and (route
        only) a harness's branches."""
        branches = [b for h in self.harnesses.values() for b in h.branches]
        return [*self.cables, *self.harnesses, *branches]

    def cable(self, name: str) -> Cable | None:
        """A cable, a harness as the bundle of all its cables, or a branch as the bundle of
        its own (None: none of them)."""
        if name in self.cables:
            return self.cables[name]
        harness = self.harnesses.get(name)
        if harness is not None:
            return bundle(harness, tuple(harness.cables))
        found = self.branch_of(name)
        return None if found is None else bundle(found[1], found[1].branches[name].cables)

    def branch_of(self, name: str) -> tuple[str, Harness] | None:
        """The harness (its name and itself) that ``name`` is a branch of, if it is one."""
        for h, harness in self.harnesses.items():
            if name in harness.branches:
                return h, harness
        return None

    def single(self, cable: str) -> Cable | HarnessCable | None:
        """A single cable by its name: one of ``cables`` or one of a harness's."""
        for harness in self.harnesses.values():
            if cable in harness.cables:
                return harness.cables[cable]
        return self.cables.get(cable)

    def cables_of(self, name: str) -> tuple[str, ...]:
        """The single cables ``name`` stands for: itself, or a harness's or a branch's in
        their order at the connector (bottom row first)."""
        if name in self.harnesses:
            harness = self.harnesses[name]
            return harness.in_order(list(harness.cables))
        found = self.branch_of(name)
        return (name,) if found is None else found[1].in_order(found[1].branches[name].cables)

    @field_validator("harnesses")
    @classmethod
    def _harness_names(
        cls, harnesses: dict[str, Harness], info: ValidationInfo
    ) -> dict[str, Harness]:
        """A name says which object it is: no harness, its cables or branches share a name
        with a cable or with each other."""
        seen = {n: "a cable" for n in info.data.get("cables", {})}
        for h, harness in harnesses.items():
            for name, what in (
                (h, "a harness"),
                *((c, f"a cable of harness {h}") for c in harness.cables),
                *((b, f"a branch of harness {h}") for b in harness.branches),
            ):
                if name in seen:
                    raise ValueError(f"{name} is both {seen[name]} and {what}: rename one")
                seen[name] = what
        return harnesses

    @model_validator(mode="after")
    def _markers_once(self) -> Objects:
        seen: dict[int, str] = {}
        for name, c in self.containers.items():
            if c.marker is not None and c.marker in seen:
                raise ValueError(f"marker {c.marker} is on both {seen[c.marker]} and {name}")
            if c.marker is not None:
                seen[c.marker] = name
        return self
