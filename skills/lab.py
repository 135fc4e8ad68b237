"""Lab-automation skills (the cooperative lab platform). Parameters now; motion in #5."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, field_validator

from cellengine.info.units import Angle, Number
from cellengine.skill import KeypointRef, ObjectRef, Skill


class Pick(Skill):
    skill: Literal["Pick"]
    object: ObjectRef
    from_: KeypointRef | None = Field(None, alias="from")  # default: where the object is


class Place(Skill):
    skill: Literal["Place"]
    object: ObjectRef
    to: KeypointRef


class Handover(Skill):
    """One arm puts the object at a shared keypoint; the other picks it up there."""

    skill: Literal["Handover"]
    object: ObjectRef
    at: KeypointRef | None = None  # default: the allocator's handover keypoint


class Unscrew(Skill):
    """One arm holds the container, the other turns its cap off."""

    skill: Literal["Unscrew"]
    object: ObjectRef
    turns: Number | None = Field(None, gt=0)  # default: the cap's turns


class Weigh(Skill):
    skill: Literal["Weigh"]
    object: ObjectRef


class Pour(Skill):
    """Tilt an open container over a target and back."""

    skill: Literal["Pour"]
    object: ObjectRef
    into: ObjectRef
    angle: Angle = Field(math.radians(100.0), gt=0)

    @field_validator("angle")
    @classmethod
    def _at_most_half_turn(cls, angle: float) -> float:
        # runs after unit conversion, so degrees and radians both work
        if angle > math.pi:
            raise ValueError("a pour tilts at most 180 deg (pi rad)")
        return angle


class BimanualCarry(Skill):
    """Both hands grasp one object (a box) on opposite sides and carry it to ``to`` keeping
    their relative pose (a closed chain: the follower tracks the leader)."""

    skill: Literal["BimanualCarry"]
    object: ObjectRef
    to: KeypointRef
