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


def count(n: int, what: str) -> BeforeValidator:
    """Check a list's length up front so the message says what was expected."""

    def check(v: Any) -> Any:
        if isinstance(v, list | tuple) and len(v) != n:
            raise ValueError(f"expected {n} {what}, got {len(v)}")
        return v

    return BeforeValidator(check)


# ints welcome; strings, booleans and YAML's .nan and .inf are not numbers
Number = Annotated[float, Strict(), AllowInfNan(False)]
Length = Annotated[float, Strict(), AllowInfNan(False), _scaler("length")]
Angle = Annotated[float, Strict(), AllowInfNan(False), _scaler("angle")]
Mass = Annotated[float, Strict(), AllowInfNan(False), _scaler("mass")]
Vec3Length = Annotated[tuple[Length, Length, Length], count(3, "numbers [x, y, z]")]
Vec3Angle = Annotated[tuple[Angle, Angle, Angle], count(3, "numbers [roll, pitch, yaw]")]
