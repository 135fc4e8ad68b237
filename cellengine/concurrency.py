"""What lets a family's segments of different arms run at once: pure data, built by the
family (a lab plan's mission), used by the stream scheduler (execute/streams.py).

Each segment belongs to a *part* (``Segment.facts[key]``: a task and the index of one of
its parts) or to none (a sync point: it starts when everything before it has ended, and
everything after it waits for its end). A segment starts after the earlier segments of its
own arms, of the earlier parts of its task and of the tasks it comes after, and of the
objects it touches (grasps, lets go of, holds, touches on purpose). A shared zone takes
one arm's TCP at a time, unless both came in for the same ``together`` part (a
cooperation: one hand holds a vial while the other turns its cap), in which the arms keep
the cell's clearance rather than the larger one of arms working apart.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from cellengine.arrays import Vec

Part = tuple[str, int]  # (task, index of its part)


@dataclass(frozen=True)
class SharedZone:
    """A box of the cell frame (m) that the TCPs of ``arms`` enter one at a time."""

    name: str
    lo: tuple[float, ...]  # x, y, z
    hi: tuple[float, ...]
    arms: frozenset[str]

    def inside(self, points: Vec) -> NDArray[np.bool_]:
        """Which of ``points`` (k x 3, m) are in the box (boundary included)."""
        inside = (np.asarray(points) >= self.lo) & (np.asarray(points) <= self.hi)
        return np.asarray(inside.all(axis=-1), dtype=bool)


@dataclass(frozen=True)
class Overlap:
    key: str  # the facts key naming a segment's part
    after: Mapping[str, frozenset[str]]  # task -> the tasks that end before it starts
    together: frozenset[Part] = frozenset()
    zones: tuple[SharedZone, ...] = ()

    def part(self, facts: Mapping[str, object]) -> Part | None:
        value: Any = facts.get(self.key)
        if value is None:
            return None
        return (str(value[0]), int(value[1]))
