"""objects.yaml ``harnesses`` (issue #15): a wire harness is a first connector with cables
leaving it at pins, grouped into branches that are routed as one bundle each.

```yaml
harnesses:
  WH1:
    connector: {type: VGA, length: 35, width: 31, height: 16}
    cables:                       # each leaves the connector at pin [row, col]
      CA1: {length: 500, diameter: 2.1, color: red, pin: [1, 1]}
      CA2: {length: 450, diameter: 2.1, color: blue, pin: [2, 1]}
    branches:                     # every cable in exactly one branch
      GR11: {cables: [CA1, CA2]}
```

Rows count up from the bottom of the connector, as REMODEL's vision service counts them
(HARNESS.md 1.6): a group's order at the connector is its cables sorted by (row, col).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from pydantic import Field, model_validator

from cellengine.info.cell import Name
from cellengine.info.connector import Connector
from cellengine.info.units import Frozen, Length, Mass

# The diameter of the smallest circle holding n equal circles of diameter 1 (the densest
# known packings, n = 1..10); a group's bundle is taken as such a packing of its cables.
_PACKED = (1.0, 2.0, 2.1547, 2.4142, 2.7013, 3.0, 3.0, 3.3048, 3.6131, 3.8130)


class HarnessCable(Frozen):
    length: Length = Field(gt=0)
    diameter: Length = Field(gt=0)
    color: str | None = None
    pin: tuple[int, int]  # [row, col] at the first connector, rows from the bottom
    end_pin: tuple[int, int] | None = None  # at the branch's end connector, if it has one
    mass: Mass | None = Field(None, ge=0)


class Branch(Frozen):
    cables: tuple[Name, ...] = Field(min_length=1)


class Harness(Frozen):
    connector: Connector
    color: str | None = None
    cables: dict[Name, HarnessCable] = Field(min_length=1)
    branches: dict[Name, Branch] = {}

    @model_validator(mode="after")
    def _branches_partition(self) -> Harness:
        """Every branch names cables of this harness, each cable is in at most one branch
        and, when branches are given, in one; no two cables share a pin."""
        owner: dict[str, str] = {}
        for name, branch in self.branches.items():
            for cable in branch.cables:
                if cable not in self.cables:
                    known = ", ".join(self.cables)
                    raise ValueError(f"branch {name} names cable {cable}; the cables are {known}")
                if cable in owner:
                    raise ValueError(f"cable {cable} is in branch {owner[cable]} and {name}")
                owner[cable] = name
        loose = [c for c in self.cables if c not in owner]
        if self.branches and loose:
            raise ValueError(f"cable{'s' * (len(loose) > 1)} {', '.join(loose)} in no branch")
        pins: dict[tuple[int, int], str] = {}
        for name, wire in self.cables.items():
            if wire.pin in pins:
                raise ValueError(f"cables {pins[wire.pin]} and {name} share pin {list(wire.pin)}")
            pins[wire.pin] = name
        return self

    def in_order(self, cables: Sequence[str]) -> tuple[str, ...]:
        return tuple(sorted(cables, key=lambda c: self.cables[c].pin))

    def bundle_diameter(self, cables: Sequence[str]) -> float:
        """The diameter of ``cables`` bundled (:func:`packed_diameter`)."""
        return packed_diameter([self.cables[c].diameter for c in cables])


def packed_diameter(diameters: Sequence[float]) -> float:
    """The diameter of cables bundled: the packing of as many equal cables of the same
    cross-section area, never less than the thickest (beyond ten cables, the area at 80 %
    fill)."""
    d = list(diameters)
    equal = math.sqrt(sum(x * x for x in d) / len(d))
    n = len(d)
    ratio = _PACKED[n - 1] if n <= len(_PACKED) else math.sqrt(n / 0.8)
    return max(max(d), ratio * equal)
