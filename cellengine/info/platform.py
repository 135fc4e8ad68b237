"""A platform's elements and keypoints, in metres, in the platform frame.

Built by a format reader (native X3D + models.xml + map.csv, or REMODEL) and consumed by
the world model. Frozen dataclasses rather than pydantic: they carry numpy arrays and meshes.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from cellengine.arrays import Mat
from cellengine.errors import Problem
from cellengine.info.mesh import Mesh


def frozen_array(a: Mat) -> Mat:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True)
class Source:
    """Where something was defined, for error messages."""

    file: str
    line: int | None = None


@dataclass(frozen=True)
class Keypoint:
    name: str
    T_element_keypoint: Mat
    dimensions: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))


@dataclass(frozen=True)
class CollisionBox:
    """A box of ``size`` (x, y, z) centred at ``T_element_box``."""

    size: tuple[float, float, float]
    T_element_box: Mat


@dataclass(frozen=True)
class Element:
    name: str  # the name plans use
    model: str
    T_platform_element: Mat  # rigid
    dimensions: Mapping[str, float]
    keypoints: Mapping[str, Keypoint]  # ordered: the first is the element's default
    mesh: Mesh | None = None  # geometry in the element frame
    boxes: tuple[CollisionBox, ...] = ()
    source: Source | None = None
    note: str = ""  # why an element has no keypoints, when that is worth saying


@dataclass(frozen=True)
class Platform:
    name: str
    T_cell_platform: Mat
    elements: Mapping[str, Element]
    # what a user should know and the files do not forbid (a CAD part no row maps)
    warnings: tuple[Problem, ...] = ()
