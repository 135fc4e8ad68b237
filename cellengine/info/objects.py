"""objects.yaml (DESIGN 3.3): cables and containers."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, model_validator

from cellengine.info.camera import MarkerId
from cellengine.info.cell import Name
from cellengine.info.pose import Pose
from cellengine.info.units import Frozen, Length, Mass, Number, Units


class Connector(Frozen):
    type: str
    length: Length = Field(gt=0)
    width: Length = Field(gt=0)
    height: Length = Field(gt=0)


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


class Objects(Frozen):
    units: Units = Units()
    cables: dict[Name, Cable] = {}
    containers: dict[Name, Container] = {}

    def names(self) -> list[str]:
        return [*self.cables, *self.containers]

    @model_validator(mode="after")
    def _markers_once(self) -> Objects:
        seen: dict[int, str] = {}
        for name, c in self.containers.items():
            if c.marker is not None and c.marker in seen:
                raise ValueError(f"marker {c.marker} is on both {seen[c.marker]} and {name}")
            if c.marker is not None:
                seen[c.marker] = name
        return self
