"""Loading a cell, its objects and a plan into a checked World and Plan.

Every problem found in one file is reported together; a file that fails stops what
depends on it (a plan is not checked against a cell that did not load).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from cellengine import geometry
from cellengine.errors import InputError, Problem, known
from cellengine.family import families
from cellengine.info.cell import BUILTIN_ROBOTS, Cell, PlatformSpec, UrdfModel
from cellengine.info.far import out_of_reach
from cellengine.info.files import resolve_inside
from cellengine.info.objects import Objects
from cellengine.info.overlaps import overlaps
from cellengine.info.plan import Plan, parse_plan
from cellengine.info.platform import Platform, frozen_array
from cellengine.info.settings import overlaid
from cellengine.info.units import Units
from cellengine.info.validation import dotted, validate
from cellengine.info.yamlio import YamlDoc, load_yaml
from cellengine.world import RefError, World

UR_JOINTS = 6


def _units(doc: YamlDoc) -> Units:
    if isinstance(doc.data, dict) and "units" in doc.data:
        return validate(Units, doc, data=doc.data["units"], prefix=("units",))
    return Units()


def _require_mapping(doc: YamlDoc, what: str) -> None:
    if not isinstance(doc.data, dict):
        article = "an" if what[0] in "aeiou" else "a"
        raise InputError.at(f"{article} {what} file must be a mapping of keys", doc.file, 1, 1)


def load_cell(path: Path) -> tuple[Cell, YamlDoc]:
    doc = overlaid(load_yaml(path), "cell")
    _require_mapping(doc, "cell")
    cell = validate(Cell, doc, _units(doc).context())
    problems = _check_cell(cell, doc)
    if problems:
        raise InputError(problems)
    return cell, doc


def _cell_warnings(cell: Cell, doc: YamlDoc) -> list[Problem]:
    """What a cell file allows but is likely a mistake: a home written in radians in a file
    of degrees (every value within half a turn and not whole: the arm starts somewhere else
    than meant, within its limits)."""
    out = _bases_apart(cell, doc)
    if _units(doc).angle != "deg":
        return out
    for name, robot in cell.robots.items():
        raw = [math.degrees(v) for v in robot.home or ()]
        if (
            raw
            and max(map(abs, raw)) <= math.pi + 1e-6
            and any(abs(v - round(v)) > 1e-6 for v in raw)
        ):
            message = (
                f"robots.{name}.home: every value is within +-3.15 and not whole: radians? "
                "this file's angles are degrees (units: {angle: deg})"
            )
            out.append(doc.error(message, ("robots", name, "home")).problems[0])
    return out


BASES_APART = 0.15  # m: about a UR arm's base across; robots closer stand on one another
SAME_PLACE = 1e-3  # m: two bases this close are one base given twice (an error)


def _bases_apart(cell: Cell, doc: YamlDoc) -> list[Problem]:
    """Two robots whose bases stand closer than BASES_APART (one base given twice)."""
    out = []
    names = list(cell.robots)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            d = math.dist(cell.robots[a].base.xyz, cell.robots[b].base.xyz)
            if SAME_PLACE <= d < BASES_APART:
                message = (
                    f"robots.{b}.base: {d * 1000:.0f} mm from robots.{a}'s base: both robots "
                    "on one base? (a UR arm's base is about 150 mm across)"
                )
                out.append(doc.error(message, ("robots", b, "base")).problems[0])
    return out


def _check_cell(cell: Cell, doc: YamlDoc) -> list[Problem]:
    out: list[Problem] = []

    def err(message: str, *loc: str | int, key: bool = False) -> None:
        out.append(doc.error(message, loc, key).problems[0])

    names = list(cell.robots)
    for i, b in enumerate(names):
        for a in names[:i]:
            if math.dist(cell.robots[a].base.xyz, cell.robots[b].base.xyz) < SAME_PLACE:
                err(
                    f"robots.{b}.base: where robots.{a}'s base is; each robot has its own",
                    *("robots", b, "base"),
                )

    def inside(ref: str, *loc: str | int) -> None:
        """A file the cell names must be inside the cell's folder."""
        try:
            resolve_inside(doc.file.parent, ref, doc.file, *_at(doc, loc))
        except InputError as e:
            out.extend(e.problems)

    carriers: dict[str, str] = {}
    for name, robot in cell.robots.items():
        tool = cell.tools.get(robot.tool or "")
        if tool is not None and tool.slot is not None and robot.tool in carriers:
            err(
                f"robots.{name}.tool: '{robot.tool}' has a slot in the tool changer, so it is "
                f"one tool, and robots.{carriers[robot.tool]} carries it: give each robot a "
                "tool of its own",
                *("robots", name, "tool"),
            )
        carriers.setdefault(robot.tool or "", name)
        if robot.tool is not None and robot.tool not in cell.tools:
            err(
                f"robots.{name}.tool: unknown tool '{robot.tool}'" + known(cell.tools),
                "robots",
                name,
                "tool",
            )
        if robot.srdf is not None:
            inside(robot.srdf, "robots", name, "srdf")
        if isinstance(robot.model, UrdfModel):
            inside(robot.model.urdf, "robots", name, "model", "urdf")
        elif robot.model not in BUILTIN_ROBOTS:
            err(
                f"robots.{name}.model: unknown robot model '{robot.model}'"
                + known(BUILTIN_ROBOTS)
                + "; or give {urdf: path, tip: link}",
                "robots",
                name,
                "model",
            )
        elif robot.home is not None and len(robot.home) != UR_JOINTS:
            err(
                f"robots.{name}.home: a {robot.model} has {UR_JOINTS} joints, got "
                f"{len(robot.home)} angles",
                "robots",
                name,
                "home",
            )
    for tname, tool in cell.tools.items():
        if tool.mesh is not None:
            inside(tool.mesh, "tools", tname, "mesh")
    for zname, zone in cell.zones.items():
        for i, robot_name in enumerate(zone.robots):
            if robot_name not in cell.robots:
                err(
                    f"zones.{zname}.robots[{i}]: unknown robot '{robot_name}'" + known(cell.robots),
                    "zones",
                    zname,
                    "robots",
                    i,
                )
    driver = cell.driver
    if driver.kind == "ur_rtde":
        for arm in driver.arms:
            if arm not in cell.robots:
                err(
                    f"driver.arms.{arm}: unknown robot '{arm}'" + known(cell.robots),
                    "driver",
                    "arms",
                    arm,
                    key=True,
                )
        for name in cell.robots:
            if name not in driver.arms:
                err(f"driver.arms: no address for robot '{name}'", "driver", "arms")
        modes = {m for tool in cell.tools.values() for m in tool.jaw}
        for mode in driver.gripper_io:
            if mode not in modes:
                err(
                    f"driver.gripper_io.{mode}: no tool has a jaw mode '{mode}'" + known(modes),
                    "driver",
                    "gripper_io",
                    mode,
                    key=True,
                )
    return out


def _at(doc: YamlDoc, loc: tuple[str | int, ...]) -> tuple[int | None, int | None]:
    pos = doc.where(loc)
    return pos if pos else (None, None)


def load_platform(name: str, spec: PlatformSpec, doc: YamlDoc) -> Platform:
    root = doc.file.parent

    def ref(key: str) -> Path:
        value = getattr(spec, key)
        return resolve_inside(root, value, doc.file, *_at(doc, ("platforms", name, key)))

    T = spec.pose.matrix()
    cad, models = ref("cad"), ref("models")
    if spec.format == "remodel":
        from cellengine.info.remodel import load_remodel_platform

        platform = load_remodel_platform(name, T, cad, ref("ids"), models, root, spec.up)
    else:
        from cellengine.info.native import load_native_platform

        platform = load_native_platform(name, T, cad, models, ref("map"), root, spec.up)
    return _moved(platform, spec, doc)


def _moved(platform: Platform, spec: PlatformSpec, doc: YamlDoc) -> Platform:
    """``platform`` with the elements cell.yaml places itself (``elements``) moved there."""
    elements = dict(platform.elements)
    for element, pose in spec.elements.items():
        if element not in elements:
            loc = ("platforms", platform.name, "elements", element)
            raise doc.error(
                f"unknown element '{platform.name}.{element}'" + known(elements), loc, key=True
            )
        T = elements[element].T_platform_element.copy()
        if pose.xyz is not None:
            T[:3, 3] = pose.xyz
        if pose.rpy is not None:
            T[:3, :3] = geometry.pose((0.0, 0.0, 0.0), pose.rpy)[:3, :3]
        if pose.move is not None:  # a shift in the cell, into the platform's frame
            T[:3, 3] += platform.T_cell_platform[:3, :3].T @ np.asarray(pose.move)
        elements[element] = replace(elements[element], T_platform_element=frozen_array(T))
    return replace(platform, elements=elements) if spec.elements else platform


def load_objects(path: Path) -> Objects:
    return _load_objects(path)[0]


def _load_objects(path: Path) -> tuple[Objects, YamlDoc]:
    doc = overlaid(load_yaml(path), "objects")
    _require_mapping(doc, "objects")
    return validate(Objects, doc, _units(doc).context()), doc


def _check_zone_keypoints(world: World, doc: YamlDoc) -> list[Problem]:
    """A zone's handover, cooperation and free places must be keypoints of the cell."""
    out: list[Problem] = []
    for name, zone in world.cell.zones.items():
        for key in ("handovers", "cooperation", "free"):
            for i, ref in enumerate(getattr(zone, key)):
                try:
                    world.resolve(ref)
                except RefError as e:
                    loc = ("zones", name, key, i)
                    out.extend(doc.error(f"zones.{name}.{key}[{i}]: {e}", loc).problems)
    return out


def _check_slots(world: World, doc: YamlDoc) -> list[Problem]:
    """A tool's slot given as a keypoint must be one of the cell."""
    out: list[Problem] = []
    for name, tool in world.cell.tools.items():
        if tool.slot is not None and isinstance(tool.slot.at, str):
            try:
                world.resolve(tool.slot.at)
            except RefError as e:
                loc = ("tools", name, "slot", "at")
                out.extend(doc.error(f"tools.{name}.slot.at: {e}", loc).problems)
    return out


def _check_objects(world: World, doc: YamlDoc) -> list[Problem]:
    """Where each container stands must be a keypoint of the cell."""
    out: list[Problem] = []
    for name, c in world.objects.containers.items():
        if not isinstance(c.at, str):
            continue
        try:
            world.resolve(c.at)
        except RefError as e:
            out.extend(doc.error(f"containers.{name}.at: {e}", ("containers", name, "at")).problems)
    return out


def load_world(cell_path: Path, objects_path: Path | None = None) -> World:
    cell, doc = load_cell(cell_path)
    platforms: dict[str, Platform] = {}
    problems: list[Problem] = []
    for name, spec in cell.platforms.items():
        try:
            platforms[name] = load_platform(name, spec, doc)
        except InputError as e:
            problems.extend(e.problems)
    objects, objects_doc = Objects(), None
    if objects_path is not None:
        try:
            objects, objects_doc = _load_objects(objects_path)
        except InputError as e:
            problems.extend(e.problems)
    world = World(cell, cell_path, platforms, objects, tuple(_cell_warnings(cell, doc)))
    if not problems:
        problems.extend(_check_zone_keypoints(world, doc))
        problems.extend(_check_slots(world, doc))
    if objects_doc is not None and not problems:
        problems.extend(_check_objects(world, objects_doc))
    if problems:
        raise InputError(problems)
    more = overlaps(world, doc) + out_of_reach(world, doc)
    return replace(world, cell_warnings=world.cell_warnings + tuple(more))


@dataclass(frozen=True)
class LoadedPlan:
    plan: Plan
    world: World


def load_plan(
    path: Path,
    load_cell_world: Callable[[Path], World] | None = None,
    cell: Path | None = None,
) -> LoadedPlan:
    """Load a plan, its cell and objects. ``load_cell_world`` lets a caller reuse worlds
    already loaded (validating a folder loads each cell once). ``cell``: run the plan in
    this cell file instead of the one it names (the same plan on other hardware)."""
    doc = overlaid(load_yaml(path), "plan")
    _require_mapping(doc, "plan")
    plan = parse_plan(doc)
    root = path.parent
    cell_path = cell or resolve_inside(root, plan.cell, path, *_at(doc, ("cell",)))
    objects_path = None
    if plan.objects is not None:
        objects_path = resolve_inside(root, plan.objects, path, *_at(doc, ("objects",)))
    try:
        world = (load_cell_world or load_world)(cell_path)
    except InputError:
        _expect_kind(cell_path, "cell", doc)
        raise
    if objects_path is not None:
        try:
            objects, objects_doc = _load_objects(objects_path)
        except InputError:
            _expect_kind(objects_path, "objects", doc)
            raise
        world = replace(world, objects=objects)
        if problems := _check_objects(world, objects_doc):
            raise InputError(problems)
    problems = check_plan(plan, world, doc)
    if problems:
        raise InputError(problems)
    return LoadedPlan(plan, world)


# The top-level keys that tell the kinds of file apart.
_KIND_KEYS = {
    "cell": ("robots",),
    "objects": ("cables", "harnesses", "containers"),
    "plan": ("steps",),
}


def _expect_kind(path: Path, kind: str, plan: YamlDoc) -> None:
    """When a plan's ``cell`` or ``objects`` file did not load: if it is another kind of
    file, that is the plan's mistake; say so at the plan's key rather than list the other
    file's keys as unknown."""
    data = load_yaml(path).data
    if not isinstance(data, dict) or any(k in data for k in _KIND_KEYS[kind]):
        return
    for other, keys in _KIND_KEYS.items():
        found = next((k for k in keys if k in data), None)
        if other != kind and found is not None:
            raise plan.error(
                f"{kind}: '{plan.data[kind]}' is {'an' if other[0] == 'o' else 'a'} {other} "
                f"file (it has '{found}'), not {'an' if kind[0] == 'o' else 'a'} {kind} file",
                (kind,),
            )


def check_plan(plan: Plan, world: World, doc: YamlDoc) -> list[Problem]:
    """Every name in every step resolves in the world; then what the steps mean there (the
    families' ``check``: mistakes named in the board's terms before any motion)."""
    out: list[Problem] = []
    arms = [*world.cell.robots, "both", "auto"]
    for i, step in enumerate(plan.steps):
        if step.arm not in arms:
            msg = f"steps[{i}].arm: unknown arm '{step.arm}'" + known(arms)
            out.append(doc.error(msg, ("steps", i, "arm")).problems[0])
        for loc, kind, name in step.refs():
            try:
                world.check(kind, name)
            except RefError as e:
                where: tuple[Any, ...] = ("steps", i, *loc)
                out.append(doc.error(f"{dotted(where)}: {e}", where).problems[0])
    if out:
        return out
    of_skill = families().of_skill
    for family in dict.fromkeys(of_skill[s.skill] for s in plan.steps):
        check = getattr(family, "check", None)
        for where, message in check(world, plan.steps) if check is not None else ():
            out.append(doc.error(f"{dotted(where)}: {message}", where).problems[0])
    return out
