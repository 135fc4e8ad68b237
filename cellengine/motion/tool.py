"""A tool's collision solids in the flange frame, and where its fingers are at each jaw opening.

cell.yaml's ``tools.<name>`` gives them as ``mesh`` (its convex hull), ``shape`` (boxes and
cylinders) and ``fingers`` (two boxes either side of the TCP along its y, the jaw axis), in that
order; the first solid is named ``tool`` and the others ``tool/<name>`` (a shape part without a
name is ``tool/part<k>``, k counting from 1 in ``shape``; the fingers ``tool/finger_left`` on
the TCP's +y, ``tool/finger_right`` on its -y). A tool with none of them is a box from the
flange to the TCP, ``finger_width`` square, as before tools carried their own geometry.

Fingers move with the jaw: the arm's model holds them at the widest opening of the tool's
modes (so a check that does not know the mode never misses a collision), and
:meth:`Fingers.placements` gives them at any other opening.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import coal
import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat
from cellengine.info.cell import FINGER_NAMES, Tool

TOOL_GEOMETRY = "tool"
DEFAULT_FINGER_WIDTH = 0.02  # m, the stand-in box's width when the tool gives none


@dataclass(frozen=True)
class Solid:
    name: str  # 'tool' or 'tool/<part>', without the arm
    T_flange_solid: Mat
    shape: Any  # coal shape centred at its frame


@dataclass(frozen=True, eq=False)
class Fingers:
    """An arm's two fingers: (thickness, width, length) along the TCP's x, y, z, and the
    opening (m) of each jaw mode."""

    size: tuple[float, float, float]
    jaw: Mapping[str, float]
    T_flange_tcp: Mat

    @property
    def names(self) -> tuple[str, str]:
        return (f"{TOOL_GEOMETRY}/{FINGER_NAMES[0]}", f"{TOOL_GEOMETRY}/{FINGER_NAMES[1]}")

    @property
    def widest(self) -> float:
        return max(self.jaw.values())

    @property
    def narrowest(self) -> float:
        return min(self.jaw.values())

    def opening(self, mode: str) -> float:
        """The mode's opening; an unknown mode counts as the widest (never misses a contact)."""
        return self.jaw.get(mode, self.widest)

    def placements(self, opening: float) -> tuple[Mat, Mat]:
        """T_flange_finger of the left (+y) and right (-y) finger: inner faces opening/2 from
        the TCP, tips at the TCP."""
        _, w, length = self.size
        offset = opening / 2.0 + w / 2.0
        return tuple(  # type: ignore[return-value]
            self.T_flange_tcp @ g.transform(np.eye(3), (0.0, s * offset, -length / 2.0))
            for s in (1.0, -1.0)
        )

    def swept(self) -> tuple[tuple[Mat, Mat], tuple[float, float, float]]:
        """Each finger's travel from the narrowest opening to the widest as one box: the
        placements and its size."""
        t, w, length = self.size
        mid = (self.widest + self.narrowest) / 2.0
        travel = (self.widest - self.narrowest) / 2.0
        return self.placements(mid), (t, w + travel, length)


def fingers_of(tool: Tool, T_flange_tcp: Mat) -> Fingers | None:
    if tool.fingers is None:
        return None
    return Fingers(tool.fingers.size, dict(tool.jaw), np.array(T_flange_tcp, dtype=float))


def tool_solids(tool: Tool, T_flange_tcp: Mat, mesh_hull: Callable[[str], Any]) -> list[Solid]:
    """The tool's solids in the flange frame, the fingers at their widest; ``mesh_hull``
    reads the tool's mesh into a convex shape."""
    shaped: list[tuple[str | None, Mat, Any]] = []
    if tool.mesh is not None:
        shaped.append(("mesh", np.eye(4), mesh_hull(tool.mesh)))
    for k, part in enumerate(tool.shape or ()):
        shaped.append((part.name or f"part{k + 1}", part.pose.matrix(), _part_shape(part)))
    fingers = fingers_of(tool, T_flange_tcp)
    if fingers is not None:
        box = coal.Box(*fingers.size)
        for name, T in zip(FINGER_NAMES, fingers.placements(fingers.widest), strict=True):
            shaped.append((name, T, box))
    if not shaped:
        return _stand_in(tool, T_flange_tcp)
    body = tool.mesh is not None or bool(tool.shape)
    return [
        Solid(TOOL_GEOMETRY if k == 0 and body else f"{TOOL_GEOMETRY}/{name}", T, shape)
        for k, (name, T, shape) in enumerate(shaped)
    ]


def _part_shape(part: Any) -> Any:
    if part.box is not None:
        return coal.Box(*map(float, part.box))
    return coal.Cylinder(float(part.cylinder.radius), float(part.cylinder.length))


def _stand_in(tool: Tool, T_flange_tcp: Mat) -> list[Solid]:
    """A box from the flange to the TCP, finger_width square (no volume for a TCP on the
    flange)."""
    p_tcp = np.asarray(T_flange_tcp)[:3, 3]
    length = float(np.linalg.norm(p_tcp))
    if length < 1e-6:
        return []
    width = tool.finger_width or DEFAULT_FINGER_WIDTH
    T = g.transform(g.z_along(p_tcp / length), p_tcp / 2)
    return [Solid(TOOL_GEOMETRY, T, coal.Box(width, width, length))]


def is_tool(name: str, arm: str) -> bool:
    """Whether the collision object ``name`` is a part of ``arm``'s tool."""
    own = f"{arm}/{TOOL_GEOMETRY}"
    return name == own or name.startswith(own + "/")
