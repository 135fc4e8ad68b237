"""The world model: keypoints in the cell frame, element dimensions, objects.

Answers questions such as the pose of ``routing.guide2.slot`` in the cell frame, the
dimensions of ``routing.guide2``, the diameter of ``cable1``, every keypoint of a platform.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

from cellengine.arrays import Mat
from cellengine.errors import Problem, known
from cellengine.info.cell import Cell
from cellengine.info.mapcsv import OBSTACLE
from cellengine.info.objects import Cable, Container, Objects
from cellengine.info.platform import Element, Keypoint, Platform


class RefError(LookupError):
    """A name that does not resolve; the message says what is known."""

    def __str__(self) -> str:
        return str(self.args[0])


@dataclass(frozen=True)
class World:
    cell: Cell
    cell_file: Path
    platforms: Mapping[str, Platform]
    objects: Objects
    cell_warnings: tuple[Problem, ...] = ()  # the cell file's (info/load.py)

    @property
    def warnings(self) -> tuple[Problem, ...]:
        """What the files allow but a user should know: the cell file's, each platform's."""
        return self.cell_warnings + tuple(w for p in self.platforms.values() for w in p.warnings)

    @property
    def tools(self) -> dict[str, str | None]:
        """The tool each robot carries (None: a bare flange)."""
        return {name: r.tool for name, r in self.cell.robots.items()}

    def with_tools(self, tools: Mapping[str, str | None]) -> World:
        """This world with the robots named in ``tools`` carrying those tools instead (a tool
        change); every other tool that has a slot waits in it (:meth:`parked`)."""
        robots = {
            n: r.model_copy(update={"tool": tools[n]}) if n in tools else r
            for n, r in self.cell.robots.items()
        }
        return replace(self, cell=self.cell.model_copy(update={"robots": robots}))

    def slot(self, tool: str) -> Mat:
        """T_cell_flange of a flange seated on ``tool`` in its changer slot."""
        spec = self.cell.tools[tool].slot
        if spec is None:
            raise RefError(f"tool '{tool}' has no slot in the tool changer (tools.{tool}.slot)")
        return self.pose(spec.at) if isinstance(spec.at, str) else spec.at.matrix()

    def parked(self) -> dict[str, Mat]:
        """Every tool that has a slot and that no robot carries: T_cell_flange of it seated."""
        carried = {r.tool for r in self.cell.robots.values()}
        return {
            name: self.slot(name)
            for name, tool in self.cell.tools.items()
            if tool.slot is not None and name not in carried
        }

    def resolve(self, ref: str, kind: str = "keypoint") -> tuple[Platform, Element, Keypoint]:
        """``platform.element[.keypoint]``; without a keypoint, the element's first."""
        parts = ref.split(".", 2)
        if len(parts) < 2 or not all(parts):
            raise RefError(f"'{ref}' is not a {kind} reference; write platform.element[.keypoint]")
        platform = self.platforms.get(parts[0])
        if platform is None:
            raise RefError(f"unknown platform '{parts[0]}' in '{ref}'" + known(self.platforms))
        element = platform.elements.get(parts[1])
        if element is None:
            what = "guide" if kind == "guide" else "element"
            names = [n for n, e in platform.elements.items() if e.model != OBSTACLE]
            raise RefError(f"unknown {what} '{parts[0]}.{parts[1]}'" + known(names))
        if not element.keypoints:
            why = f": {element.note}" if element.note else ""
            raise RefError(f"element '{parts[0]}.{parts[1]}' has no keypoints{why}")
        name = parts[2] if len(parts) == 3 else next(iter(element.keypoints))
        keypoint = element.keypoints.get(name)
        if keypoint is None:
            raise RefError(f"unknown keypoint '{ref}'" + known(element.keypoints))
        return platform, element, keypoint

    def pose(self, ref: str) -> Mat:
        """T_cell_keypoint = T_cell_platform · T_platform_element · T_element_keypoint."""
        p, e, k = self.resolve(ref)
        return p.T_cell_platform @ e.T_platform_element @ k.T_element_keypoint

    def standing(self, c: Container) -> Mat:
        """T_cell_base of a container where it stands at the start (its ``at``, given)."""
        if c.at is None:
            raise ValueError("the container has no `at`")
        return self.pose(c.at) if isinstance(c.at, str) else c.at.matrix()

    def element(self, ref: str) -> Element:
        parts = ref.split(".")
        if len(parts) != 2:
            raise RefError(f"'{ref}' is not an element reference; write platform.element")
        return self._element(*parts)

    def dimensions(self, ref: str) -> Mapping[str, float]:
        """An element's dimensions, or a keypoint's own merged over its element's."""
        if ref.count(".") == 1:
            return self.element(ref).dimensions
        _, e, k = self.resolve(ref)
        return {**e.dimensions, **k.dimensions}

    def keypoints(self, platform: str | None = None) -> dict[str, Mat]:
        """Every keypoint (of one platform, or all) in the cell frame, by full name."""
        names = [platform] if platform is not None else list(self.platforms)
        out: dict[str, Mat] = {}
        for pname in names:
            if pname not in self.platforms:
                raise RefError(f"unknown platform '{pname}'" + known(self.platforms))
            p = self.platforms[pname]
            for e in p.elements.values():
                T = p.T_cell_platform @ e.T_platform_element
                for k in e.keypoints.values():
                    out[f"{pname}.{e.name}.{k.name}"] = T @ k.T_element_keypoint
        return out

    def cable(self, name: str) -> Cable:
        """A cable, or a harness as one bundle of its cables."""
        cable = self.objects.cable(name)
        if cable is None:
            raise RefError(f"unknown cable '{name}'" + known(self.objects.cable_names()))
        return cable

    def container(self, name: str) -> Container:
        if name not in self.objects.containers:
            raise RefError(f"unknown container '{name}'" + known(self.objects.containers))
        return self.objects.containers[name]

    def check(self, kind: str, name: str) -> None:
        """Raise RefError unless ``name`` resolves as a ``kind``."""
        if kind in ("keypoint", "guide"):
            self.resolve(name, kind)
        elif kind == "cable":
            self.cable(name)
        elif kind == "container":
            self.container(name)
        elif kind == "tool":
            if name not in self.cell.tools:
                raise RefError(f"unknown tool '{name}'" + known(self.cell.tools))
            self.slot(name)
        elif kind == "object":
            if name not in self.objects.names():
                raise RefError(f"unknown object '{name}'" + known(self.objects.names()))
        else:
            raise ValueError(f"unknown reference kind {kind!r}")

    def _element(self, pname: str, ename: str) -> Element:
        p = self.platforms.get(pname)
        if p is None:
            raise RefError(f"unknown platform '{pname}'" + known(self.platforms))
        if ename not in p.elements:
            raise RefError(f"unknown element '{pname}.{ename}'" + known(p.elements))
        return p.elements[ename]
