"""Cable-routing skills (the published REMODEL method). Parameters now; motion in #4."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field

from cellengine.info.units import count
from cellengine.skill import CableRef, GuideRef, KeypointRef, Skill, register


@register
class PickCable(Skill):
    """Grasp both ends of a cable from two combs, connector end first."""

    skill: Literal["PickCable"]
    cable: CableRef
    from_: Annotated[
        tuple[KeypointRef, KeypointRef], count(2, "keypoints [connector end, other end]")
    ] = Field(alias="from")


@register
class PlaceConnector(Skill):
    """Insert the cable's connector into a connector guide."""

    skill: Literal["PlaceConnector"]
    cable: CableRef
    guide: GuideRef


@register
class RouteCable(Skill):
    """Route the cable through guides, in order."""

    skill: Literal["RouteCable"]
    cable: CableRef
    guides: tuple[GuideRef, ...] = Field(min_length=1)
