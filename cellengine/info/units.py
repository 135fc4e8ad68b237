"""Units in files, converted once at load to m / rad / kg.

Quantities are annotated types that scale by a factor passed in the validation context,
so a model holds SI values and its JSON Schema still shows plain numbers.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import (
    AfterValidator,
    AllowInfNan,
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Strict,
    ValidationInfo,
)

from cellengine.info.bounds import MAX_COORDINATE, MAX_MASS

LENGTH = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
ANGLE = {"rad": 1.0, "deg": math.pi / 180.0}
MASS = {"kg": 1.0, "g": 1e-3}


class Frozen(BaseModel):
    """Base of every file model: immutable, unknown keys refused."""

    model_config = ConfigDict(extra="forbid", frozen=True)


class Units(Frozen):
    length: Literal["m", "cm", "mm"] = "m"
    angle: Literal["rad", "deg"] = "rad"
    mass: Literal["kg", "g"] = "kg"

    def context(self) -> dict[str, float]:
        return {"length": LENGTH[self.length], "angle": ANGLE[self.angle], "mass": MASS[self.mass]}


def _scaler(kind: str) -> AfterValidator:
    def scale(v: float, info: ValidationInfo) -> float:
        ctx = info.context or {}
        return v * float(ctx.get(kind, 1.0))

    return AfterValidator(scale)


def _unit(table: dict[str, float], factor: float) -> str:
    return next(name for name, f in table.items() if f == factor)


def _within(v: float, info: ValidationInfo) -> float:
    """A length within MAX_COORDINATE either way: past it a file's unit is wrong (mm read as
    m) or the number is hostile (1e300 overflows the geometry downstream)."""
    factor = float((info.context or {}).get("length", 1.0))
    limit = MAX_COORDINATE / factor  # in the file's unit: no rounding at the limit itself
    if abs(v) > limit:
        unit = _unit(LENGTH, factor)
        metres = f" ({MAX_COORDINATE:g} m)" if unit != "m" else ""
        if unit == "m" and abs(v) <= 1000.0 * limit:  # a cell's size in millimetres
            metres = " (lengths are metres unless the file says `units: {length: mm}`)"
        raise ValueError(f"must be between {-limit:g} and {limit:g} {unit}{metres}")
    return v


def _at_most_max_mass(v: float, info: ValidationInfo) -> float:
    """A mass a dual-arm cell can hold or weigh (masses are never negative: each field
    says so)."""
    factor = float((info.context or {}).get("mass", 1.0))
    limit = MAX_MASS / factor
    if v > limit:
        unit = _unit(MASS, factor)
        kg = f" ({MAX_MASS:g} kg)" if unit != "kg" else ""
        raise ValueError(f"must be at most {limit:g} {unit}{kg}")
    return v


def count(n: int, what: str) -> BeforeValidator:
    """Check a list's length up front so the message says what was expected."""

    def check(v: Any) -> Any:
        if isinstance(v, list | tuple) and len(v) != n:
            raise ValueError(f"expected {n} {what}, got {len(v)}")
        return v

    return BeforeValidator(check)


# ints welcome; strings, booleans and YAML's .nan and .inf are not numbers
Number = Annotated[float, Strict(), AllowInfNan(False)]
Length = Annotated[float, Strict(), AllowInfNan(False), AfterValidator(_within), _scaler("length")]
Angle = Annotated[float, Strict(), AllowInfNan(False), _scaler("angle")]
Mass = Annotated[
    float, Strict(), AllowInfNan(False), AfterValidator(_at_most_max_mass), _scaler("mass")
]
Vec3Length = Annotated[tuple[Length, Length, Length], count(3, "numbers [x, y, z]")]
Vec3Angle = Annotated[tuple[Angle, Angle, Angle], count(3, "numbers [roll, pitch, yaw]")]
