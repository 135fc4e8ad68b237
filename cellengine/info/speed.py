"""The speed knobs of cell.yaml and plan.yaml: ``speed`` scales the joints' velocity and
acceleration limits the trajectories are timed with (a fraction of each, or one number for
both), ``tcp_speed`` caps the tools' speed (length unit per second)."""

from __future__ import annotations

from typing import Annotated

from pydantic import AllowInfNan, Field, Strict

from cellengine.info.units import Frozen

# A share of a limit: more than nothing, at most all of it
Fraction = Annotated[float, Strict(), AllowInfNan(False), Field(gt=0, le=1)]


class SpeedScaling(Frozen):
    """Fractions of the joints' velocity and acceleration limits the timing uses."""

    velocity: Fraction = 1.0
    acceleration: Fraction = 1.0


# `speed: 0.5` is `speed: {velocity: 0.5, acceleration: 0.5}`
SpeedSpec = Fraction | SpeedScaling


def scaling(spec: SpeedSpec | None) -> SpeedScaling | None:
    """A ``speed`` as its two fractions (None: not given)."""
    if spec is None or isinstance(spec, SpeedScaling):
        return spec
    return SpeedScaling(velocity=spec, acceleration=spec)
