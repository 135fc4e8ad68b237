"""A cable's or a harness's connector in objects.yaml (DESIGN 3.3)."""

from __future__ import annotations

from pydantic import Field

from cellengine.info.units import Frozen, Length


class Connector(Frozen):
    type: str
    length: Length = Field(gt=0)
    width: Length = Field(gt=0)
    height: Length = Field(gt=0)
