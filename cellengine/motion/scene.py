"""The collision scene of a whole cell, built once: what is checked against what, and why not.

Building is separate from checking (:mod:`cellengine.motion.collision`), so tests and other
layers can inspect what was built: every object with its owner and the joint moving it, the
allowed-collision matrix (ACM) with a reason per pair, and the pairs that are checked.

Objects and their names:

- arm links from :class:`CellModel.collision` (``left/forearm_link``, ``left/tool``); an arm's
  base geometry is fixed in the cell (joint 0) but still belongs to the arm;
- platform elements, named as plans name them (``routing.guide2``; ``#2``, ... when an element
  has several boxes). A REMODEL element's ``boxes`` are its collision model. Otherwise its X3D
  mesh is a coal BVH (triangle mesh) for collision, not its convex hull: the concavities of
  these parts are where the work happens (a U guide's slot holds the cable, the connector
  guide's pocket holds the connector with 1 mm to spare) and a hull would fill them, putting
  every placing move in collision. A convex mesh is used as its hull (exact, and faster);
- obstacles of cell.yaml by their name (``table``): box, cylinder (coal's exact cylinder),
  sphere;
- held objects (:class:`HeldObject`), attached to an arm's TCP at run time by :func:`attach`.

A BVH is a surface: coal reports a shape wholly inside a closed mesh as free. That needs a wall
thicker than the smallest moving shape; :func:`build_scene` notes any element where it could
happen. BVH distances are slow in coal (about 35 us per pair against 1 us for a convex shape),
so each mesh element also has its convex hull, a lower bound on the distance to the mesh
(hull contains mesh), in the ``bounds`` model that distance queries start from.

ACM reasons, first match wins: ``static`` (neither object moves: environment against
environment, arm bases against the environment; ``stands_on`` for an arm's base against the
obstacle its base frame is on), ``same_body`` (objects on one rigid body), ``adjacent`` (one
arm's bodies joined by one joint), ``held`` (a held object and the gripper holding it),
``user``, ``srdf``, ``out_of_reach`` (the spheres each object can ever occupy, about a point
fixed in the cell, do not meet: a geometric proof), ``never``: an arm's own pairs never within
ACM_MARGIN in ACM_SAMPLES random configurations, their closest approach then lowered by local
descent (:func:`sampled_self_pairs`; once per distinct arm geometry in a scene, about 0.15 s,
so no file cache), and the objects moved by an arm's first joint alone against the
environment, swept finely enough to be a proof (:func:`sampled_first_joint_pairs`). Arm
against arm pairs are not sampled: their distance depends on all twelve joints, where 10 000
samples are far too sparse to call a pair safe; only reach spheres rule them out.

How SRDF would be wired: a ``robots.<name>.srdf`` key in cell.yaml (a path inside the cell
folder, resolved like a URDF) read by :func:`load_srdf` and passed as ``srdf={name: pairs}``.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from cellengine import geometry as g
from cellengine.arrays import Mat, Vec
from cellengine.errors import InputError
from cellengine.info.cell import Obstacle
from cellengine.info.files import resolve_inside
from cellengine.info.mesh import Mesh
from cellengine.info.xmlsafe import parse_xml
from cellengine.motion.hull import convex_hull
from cellengine.motion.robot import Arm, CellModel, finger_placements, is_tool, parked_solids
from cellengine.world import World

Pair = tuple[str, str]  # two object names, sorted
Kind = Literal["link", "static", "held"]

ACM_SAMPLES = 10_000  # random configurations per arm for the self pairs (MoveIt's default)
ACM_MARGIN = 0.002  # m: a sampled pair never closer than this is disabled
ACM_SEED = 0
# A closed mesh whose volume is its hull's to this fraction is convex. The cells' concave
# parts miss by 7 % or more; rounding in CAD coordinates is far below.
CONVEX_VOLUME = 1e-6
STANDS_ON_TOLERANCE = 0.01  # m: a base frame this close to an obstacle's box stands on it


def pair_key(a: str, b: str) -> Pair:
    return (a, b) if a <= b else (b, a)


@dataclass(frozen=True)
class ACM:
    """The allowed-collision matrix: pairs never checked, each with its reason."""

    reasons: Mapping[Pair, str]

    @property
    def pairs(self) -> frozenset[Pair]:
        return frozenset(self.reasons)

    def allowed(self, a: str, b: str) -> bool:
        return pair_key(a, b) in self.reasons

    def reason(self, a: str, b: str) -> str | None:
        return self.reasons.get(pair_key(a, b))

    def by_reason(self, reason: str) -> frozenset[Pair]:
        return frozenset(p for p, r in self.reasons.items() if r.split(" ")[0] == reason)


@dataclass(frozen=True)
class SceneObject:
    name: str
    kind: Kind  # link: an arm's link or tool; static: environment; held: attached at run time
    owner: str | None  # the arm a link or held object belongs to; None for the environment
    joint: int  # the joint moving it in the cell model; 0 = fixed in the cell


@dataclass(frozen=True, eq=False)
class StaticShape:
    """One environment object in the cell frame."""

    name: str
    T_cell_shape: Mat
    shape: Any  # coal geometry checked for collision
    bound: Any  # convex coal geometry containing `shape`: distances to it bound shape's below
    exact: bool  # bound is shape (no refinement needed)


@dataclass(frozen=True, eq=False)
class HeldObject:
    """An object in a gripper: it moves with the TCP and is checked against everything but the
    gripper holding it and the objects named in ``allowed`` (e.g. the guide it is placed in)."""

    name: str
    arm: str
    shape: Any  # coal.Box / coal.Cylinder / coal.Sphere / coal.Capsule, centred at its frame
    T_tcp_object: Mat
    allowed: frozenset[str] = frozenset()


def held_box(
    name: str, arm: str, size: Sequence[float], T_tcp_object: Mat, allowed: Iterable[str] = ()
) -> HeldObject:
    return HeldObject(name, arm, coal.Box(*map(float, size)), T_tcp_object, frozenset(allowed))


def held_cylinder(
    name: str,
    arm: str,
    radius: float,
    length: float,
    T_tcp_object: Mat,
    allowed: Iterable[str] = (),
) -> HeldObject:
    """A cylinder along the object frame's z, centred at its origin."""
    return HeldObject(name, arm, coal.Cylinder(radius, length), T_tcp_object, frozenset(allowed))


def held_from_world(
    world: World, name: str, arm: str, T_tcp_object: Mat, allowed: Iterable[str] = ()
) -> HeldObject:
    """A cable's connector (``cable1.connector``: a box length x width x height) or a
    container (``vial1``: a cylinder of its diameter and height, or a box container's size)."""
    if name.endswith(".connector"):
        connector = world.cable(name.removesuffix(".connector")).connector
        if connector is None:
            raise ValueError(f"cable '{name.removesuffix('.connector')}' has no connector")
        size = (connector.length, connector.width, connector.height)
        return held_box(name, arm, size, T_tcp_object, allowed)
    c = world.container(name)
    if c.size is not None:
        return held_box(name, arm, c.size, T_tcp_object, allowed)
    if c.diameter is None or c.height is None:
        raise ValueError(f"container '{name}' needs a diameter and a height, or a size")
    return held_cylinder(name, arm, c.diameter / 2, c.height, T_tcp_object, allowed)


@dataclass(frozen=True, eq=False)
class CollisionScene:
    """Everything a checker needs, built once per cell (and again on attach/detach)."""

    cell: CellModel
    geometry: Any  # pin.GeometryModel: every object; collisionPairs = the checked pairs
    bounds: Any  # pin.GeometryModel: the same, mesh elements as hulls; the same pairs
    objects: tuple[SceneObject, ...]  # index = geometry object id in both models
    acm: ACM
    pairs: tuple[tuple[int, int], ...]  # checked, as object ids; index = collision pair id
    exact_bounds: NDArray[np.bool_]  # (P,): the bounds model gives the pair's true distance
    motion: Vec  # (P, nq): m per rad (per m) each joint can move one object relative to other
    statics: tuple[StaticShape, ...]
    held: Mapping[str, HeldObject]
    fixed_reasons: Mapping[Pair, str]  # sampled, SRDF and user pairs, kept across attach
    notes: tuple[str, ...]
    # arm -> its fingers' opening (m); an arm not named has them at its tool's widest
    jaw: Mapping[str, float] = field(default_factory=dict)
    _ids: Mapping[str, int] = field(init=False, repr=False)
    # the clearance measurement's pairs, one model per set of pairs left out, built on first
    # use by motion.clearance (which owns the type): they live and go with the scene
    clearance_model: Any = field(init=False, default=None, repr=False)
    # the checker transits keep the clearance with, built on first use by motion.margins
    margin_checker: Any = field(init=False, default=None, repr=False)

    def __post_init__(self) -> None:
        ids = MappingProxyType({o.name: i for i, o in enumerate(self.objects)})
        object.__setattr__(self, "_ids", ids)

    def index(self, name: str) -> int:
        return self._ids[name]

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(o.name for o in self.objects)

    @property
    def checked(self) -> frozenset[Pair]:
        return frozenset(self.pair_names(p) for p in range(len(self.pairs)))

    def pair_names(self, p: int) -> Pair:
        a, b = self.pairs[p]
        return pair_key(self.objects[a].name, self.objects[b].name)


# ---------------------------------------------------------------------------------- building


def build_scene(
    cell: CellModel,
    world: World,
    *,
    srdf: Mapping[str, Iterable[Pair]] | None = None,
    allowed: Iterable[Pair] = (),
    held: Iterable[HeldObject] = (),
    samples: int = ACM_SAMPLES,
    margin: float = ACM_MARGIN,
    seed: int = ACM_SEED,
) -> CollisionScene:
    """The scene of ``world``'s cell. ``srdf`` maps a robot's name to the link pairs of its
    SRDF (:func:`load_srdf`, link names as in its URDF); ``allowed`` are object-name pairs
    never to check."""
    if srdf is None:
        srdf = srdf_of(world)
    statics, notes = environment(world)
    links = _objects_of(cell)
    fixed: dict[Pair, str] = {}
    memo: SelfPairMemo = {}  # the second of two identical arms costs nothing
    for _name, arm in cell.arms.items():
        for pair, closest in sampled_self_pairs(arm, samples, margin, seed, memo).items():
            fixed[pair] = (
                f"never (none within {margin * 1000:g} mm in {samples} samples; "
                f"{closest * 1000:.1f} mm at the closest found by local descent)"
            )
    for pair in sampled_first_joint_pairs(cell, statics, margin):
        fixed[pair] = f"never (first joint swept at {margin * 500:.1f} mm steps)"
    for robot, pairs in (srdf or {}).items():
        fixed.update(_srdf_reasons(robot, pairs, [o.name for o in links], notes))
    for a, b in allowed:
        fixed[pair_key(a, b)] = "user"
    notes.extend(_enclosure_notes(cell, statics))
    return assemble(cell, statics, {h.name: h for h in held}, fixed, tuple(notes))


def attach(scene: CollisionScene, obj: HeldObject) -> CollisionScene:
    """The scene with ``obj`` held at its arm's TCP."""
    if obj.name in scene.names:
        raise ValueError(f"an object named '{obj.name}' is already in the scene")
    held = {**scene.held, obj.name: obj}
    return assemble(scene.cell, scene.statics, held, scene.fixed_reasons, scene.notes, scene.jaw)


def detach(scene: CollisionScene, name: str) -> CollisionScene:
    if name not in scene.held:
        raise KeyError(f"no held object '{name}' (held: {', '.join(scene.held) or 'none'})")
    held = {k: v for k, v in scene.held.items() if k != name}
    return assemble(scene.cell, scene.statics, held, scene.fixed_reasons, scene.notes, scene.jaw)


def with_jaw(scene: CollisionScene, jaw: Mapping[str, float]) -> CollisionScene:
    """The scene with each named arm's fingers at its opening (m); the others as they were."""
    merged = {**scene.jaw, **jaw}
    return assemble(scene.cell, scene.statics, scene.held, scene.fixed_reasons, scene.notes, merged)


def assemble(
    cell: CellModel,
    statics: Sequence[StaticShape],
    held: Mapping[str, HeldObject],
    fixed_reasons: Mapping[Pair, str],
    notes: tuple[str, ...],
    jaw: Mapping[str, float] | None = None,
) -> CollisionScene:
    """Both geometry models, the ACM and the checked pairs: cheap (no sampling). ``jaw``: arm
    -> its fingers' opening (m), else the widest."""
    jaw = dict(jaw or {})
    geometry, bounds = cell.collision.copy(), cell.collision.copy()
    for gm in (geometry, bounds):
        gm.removeAllCollisionPairs()  # pin.appendModel adds pairs of its own: ours replace them
        place_fingers(cell, gm, jaw)
    objects = list(_objects_of(cell))
    exact = [True] * len(objects)
    for s in statics:
        placement = pin.SE3(s.T_cell_shape)
        geometry.addGeometryObject(pin.GeometryObject(s.name, 0, 0, placement, s.shape))
        bounds.addGeometryObject(pin.GeometryObject(s.name, 0, 0, placement, s.bound))
        objects.append(SceneObject(s.name, "static", None, 0))
        exact.append(s.exact)
    for h in held.values():
        for gm in (geometry, bounds):
            gm.addGeometryObject(_held_geometry(cell, h))
        objects.append(SceneObject(h.name, "held", h.arm, _tcp_joint(cell, h.arm)))
        exact.append(True)
    if len({o.name for o in objects}) != len(objects):
        raise ValueError("object names in the scene are not unique")
    for gm in (geometry, bounds):
        for i in range(len(objects)):
            gm.geometryObjects[i].geometry.computeLocalAABB()
    _refuse_held_overlaps(cell, geometry, objects, held)
    reach = _reach(cell.model, geometry, objects)
    rules = _Rules(cell, geometry, objects, held, statics, fixed_reasons, reach)
    reasons: dict[Pair, str] = {}
    pairs: list[tuple[int, int]] = []
    for i in range(len(objects)):
        for j in range(i + 1, len(objects)):
            why = rules.reason(i, j)
            if why is None:
                pairs.append((i, j))
            else:
                reasons[pair_key(objects[i].name, objects[j].name)] = why
    for gm in (geometry, bounds):
        for i, j in pairs:
            gm.addCollisionPair(pin.CollisionPair(i, j))
    radii, chains = _motion_radii(cell.model, geometry, objects)
    return CollisionScene(
        cell=cell,
        geometry=geometry,
        bounds=bounds,
        objects=tuple(objects),
        acm=ACM(MappingProxyType(reasons)),
        pairs=tuple(pairs),
        exact_bounds=np.array([exact[i] and exact[j] for i, j in pairs], dtype=bool),
        motion=_pair_motion(radii, chains, pairs, cell.nq),
        statics=tuple(statics),
        held=MappingProxyType(dict(held)),
        fixed_reasons=MappingProxyType(dict(fixed_reasons)),
        notes=notes,
        jaw=MappingProxyType(jaw),
    )


def checking_too(scene: CollisionScene, extra: Iterable[tuple[int, int]]) -> CollisionScene:
    """The scene with the pairs ``extra`` (object ids, lower first) checked as well, after its
    own: pairs the ACM leaves out because they cannot touch (``out_of_reach``) may still come
    closer than a margin a checker is asked to keep. The ACM is the scene's (it says why they
    cannot touch)."""
    own = set(scene.pairs)
    added = [(i, j) for i, j in extra if (i, j) not in own]
    pairs = [*scene.pairs, *added]
    geometry, bounds = scene.geometry.copy(), scene.bounds.copy()
    for gm in (geometry, bounds):
        for i, j in added:
            gm.addCollisionPair(pin.CollisionPair(i, j))
    exact = {s.name: s.exact for s in scene.statics}
    exact_added = [
        exact.get(scene.objects[i].name, True) and exact.get(scene.objects[j].name, True)
        for i, j in added
    ]
    radii, chains = _motion_radii(scene.cell.model, geometry, scene.objects)
    return CollisionScene(
        cell=scene.cell,
        geometry=geometry,
        bounds=bounds,
        objects=scene.objects,
        acm=scene.acm,
        pairs=tuple(pairs),
        exact_bounds=np.concatenate([scene.exact_bounds, np.array(exact_added, dtype=bool)]),
        motion=_pair_motion(radii, chains, pairs, scene.cell.nq),
        statics=scene.statics,
        held=scene.held,
        fixed_reasons=scene.fixed_reasons,
        notes=scene.notes,
        jaw=scene.jaw,
    )


def place_fingers(cell: CellModel, geometry: Any, jaw: Mapping[str, float]) -> None:
    """Each named arm's fingers in ``geometry`` (a copy of the cell's) at its opening (m)."""
    for arm, opening in jaw.items():
        for name, placement in finger_placements(cell.arms[arm], opening).items():
            geometry.geometryObjects[geometry.getGeometryId(name)].placement = placement


def _objects_of(cell: CellModel) -> list[SceneObject]:
    """The arms' geometry objects, in cell.collision's order."""
    out = []
    for obj in cell.collision.geometryObjects:
        owner = str(obj.name).split("/", 1)[0]
        out.append(SceneObject(str(obj.name), "link", owner, int(obj.parentJoint)))
    return out


def _tcp_joint(cell: CellModel, arm: str) -> int:
    if arm not in cell.arms:
        raise ValueError(f"unknown arm '{arm}' (arms: {', '.join(cell.arms)})")
    return int(cell.model.frames[cell.tcp[arm]].parentJoint)


def _held_geometry(cell: CellModel, h: HeldObject) -> Any:
    tcp = cell.model.frames[cell.tcp[h.arm]] if h.arm in cell.tcp else None
    if tcp is None:
        raise ValueError(f"unknown arm '{h.arm}' (arms: {', '.join(cell.arms)})")
    placement = tcp.placement * pin.SE3(np.asarray(h.T_tcp_object, dtype=float))
    return pin.GeometryObject(h.name, tcp.parentJoint, cell.tcp[h.arm], placement, h.shape)


def _refuse_held_overlaps(
    cell: CellModel, geometry: Any, objects: Sequence[SceneObject], held: Mapping[str, HeldObject]
) -> None:
    """A held object rides on the wrist's body, so its pairs with that body's links never
    change and are not checked at run time: check them once here, gripper excepted."""
    data, gdata = cell.model.createData(), pin.GeometryData(geometry)
    pin.updateGeometryPlacements(cell.model, data, geometry, gdata, pin.neutral(cell.model))
    for i, o in enumerate(objects):
        if o.kind != "held":
            continue
        for j, other in enumerate(objects):
            if other.joint != o.joint or j == i or _is_gripper(other, held[o.name]):
                continue
            if other.name in held[o.name].allowed:
                continue
            if _collide(geometry, gdata, i, j):
                raise ValueError(f"held object '{o.name}' intersects '{other.name}' it rides with")


def _is_gripper(obj: SceneObject, h: HeldObject) -> bool:
    return obj.kind == "link" and is_tool(obj.name, h.arm)


def _collide(geometry: Any, gdata: Any, i: int, j: int) -> bool:
    a, b = geometry.geometryObjects[i], geometry.geometryObjects[j]
    request, result = coal.CollisionRequest(), coal.CollisionResult()
    T_a = coal.Transform3s(gdata.oMg[i].rotation, gdata.oMg[i].translation)
    T_b = coal.Transform3s(gdata.oMg[j].rotation, gdata.oMg[j].translation)
    return bool(coal.collide(a.geometry, T_a, b.geometry, T_b, request, result))


class _Rules:
    """Why a pair is not checked (first match wins), or None."""

    def __init__(
        self,
        cell: CellModel,
        geometry: Any,
        objects: Sequence[SceneObject],
        held: Mapping[str, HeldObject],
        statics: Sequence[StaticShape],
        fixed: Mapping[Pair, str],
        reach: tuple[Vec, Vec],
    ) -> None:
        self.cell, self.objects, self.held, self.fixed = cell, objects, held, fixed
        self.centre, self.radius = reach
        self.parents = [int(p) for p in cell.model.parents]
        self.supports = _supports(cell, statics)

    def reason(self, i: int, j: int) -> str | None:
        a, b = self.objects[i], self.objects[j]
        if a.joint == 0 and b.joint == 0:
            stands = (a.owner, b.name) in self.supports or (b.owner, a.name) in self.supports
            return "stands_on" if stands else "static"
        if self._held_by(a, b) or self._held_by(b, a):
            return "held"
        if a.joint == b.joint:
            return "same_body"
        if a.owner == b.owner and a.kind == b.kind == "link" and self._adjacent(a, b):
            return "adjacent"
        fixed = self.fixed.get(pair_key(a.name, b.name))
        if fixed is not None:
            return fixed
        gap = float(np.linalg.norm(self.centre[i] - self.centre[j]))
        if gap > self.radius[i] + self.radius[j]:
            return f"out_of_reach ({gap - self.radius[i] - self.radius[j]:.3f} m apart at least)"
        return None

    def _adjacent(self, a: SceneObject, b: SceneObject) -> bool:
        return self.parents[a.joint] == b.joint or self.parents[b.joint] == a.joint

    def _held_by(self, h: SceneObject, other: SceneObject) -> bool:
        if h.kind != "held":
            return False
        return _is_gripper(other, self.held[h.name]) or other.name in self.held[h.name].allowed


def _supports(cell: CellModel, statics: Sequence[StaticShape]) -> set[tuple[str, str]]:
    """(arm, static object) where the arm's base frame lies on or in the object's box."""
    out = set()
    for name, arm in cell.arms.items():
        p_cell_base = arm.T_cell_base[:3, 3]
        for s in statics:
            lo, hi = _aabb(s)
            if np.all(p_cell_base >= lo - STANDS_ON_TOLERANCE) and np.all(
                p_cell_base <= hi + STANDS_ON_TOLERANCE
            ):
                out.add((name, s.name))
    return out


def _aabb(s: StaticShape) -> tuple[Vec, Vec]:
    s.shape.computeLocalAABB()
    box = s.shape.aabb_local
    corners = np.array(
        [
            [x, y, z]
            for x in (box.min_[0], box.max_[0])
            for y in (box.min_[1], box.max_[1])
            for z in (box.min_[2], box.max_[2])
        ]
    )
    cell_corners = g.transform_points(s.T_cell_shape, corners)
    return cell_corners.min(axis=0), cell_corners.max(axis=0)


# ---------------------------------------------------------------------------------- environment


def environment(world: World) -> tuple[list[StaticShape], list[str]]:
    """Every platform element's collision shapes and every obstacle, in the cell frame; and
    notes on elements that have no geometry."""
    out: list[StaticShape] = []
    notes: list[str] = []
    for pname, platform in world.platforms.items():
        for ename, element in platform.elements.items():
            name = f"{pname}.{ename}"
            T_cell_element = platform.T_cell_platform @ element.T_platform_element
            if element.boxes:
                for k, box in enumerate(element.boxes):
                    shape = coal.Box(*map(float, box.size))
                    T = T_cell_element @ box.T_element_box
                    out.append(
                        StaticShape(name + (f"#{k + 1}" if k else ""), T, shape, shape, True)
                    )
            elif element.mesh is not None and len(element.mesh.faces) > 0:
                out.append(_mesh_shape(name, T_cell_element, element.mesh))
            else:
                notes.append(f"element '{name}' has no collision geometry (no boxes, no mesh)")
    for oname, obstacle in world.cell.obstacles.items():
        shape = _obstacle_shape(obstacle)
        out.append(StaticShape(oname, obstacle.pose.matrix(), shape, shape, True))
    for cname, c in world.objects.containers.items():
        if c.at is not None:
            out.append(standing_container(world, cname, world.standing(c)))
    for tool, T_cell_flange in world.parked().items():
        for name, T_cell_solid, shape in parked_solids(world, tool, T_cell_flange):
            out.append(StaticShape(name, T_cell_solid, shape, shape, True))
    return out, notes


def standing_container(world: World, name: str, T_cell_base: Mat) -> StaticShape:
    """Container ``name`` standing with its base at ``T_cell_base``: its cylinder (or box),
    named as the container, centred half its height above the base."""
    c = world.container(name)
    height = c.full_height
    if height is None or (c.diameter is None and c.size is None):
        raise ValueError(f"container '{name}' needs a size, or a height and a diameter")
    T = np.array(T_cell_base, dtype=float) @ g.transform(np.eye(3), (0.0, 0.0, height / 2))
    if c.size is not None:
        shape: Any = coal.Box(*map(float, c.size))
    else:
        assert c.diameter is not None
        shape = coal.Cylinder(c.diameter / 2, c.height)
    return StaticShape(name, T, shape, shape, True)


def rearranged(
    scene: CollisionScene,
    statics: Sequence[StaticShape],
    held: Mapping[str, HeldObject],
    allowed: Mapping[Pair, str],
) -> CollisionScene:
    """``scene`` with other environment objects (containers put elsewhere), held objects
    and more pairs never checked (``allowed``: pair -> reason); its sampled pairs kept."""
    fixed = {**scene.fixed_reasons, **allowed}
    return assemble(scene.cell, statics, held, fixed, scene.notes, scene.jaw)


def _obstacle_shape(o: Obstacle) -> Any:
    if o.box is not None:
        return coal.Box(*map(float, o.box))
    if o.cylinder is not None:
        return coal.Cylinder(o.cylinder.radius, o.cylinder.length)
    assert o.sphere is not None  # the model validator guarantees exactly one shape
    return coal.Sphere(o.sphere.radius)


def _mesh_shape(name: str, T_cell_element: Mat, mesh: Mesh) -> StaticShape:
    hull = _convex(mesh)
    if hull is not None and _is_convex(mesh, hull):
        return StaticShape(name, T_cell_element, hull, hull, True)
    bvh = _bvh(mesh)
    # A flat mesh has no hull: its BVH is its own (slow) distance bound.
    return StaticShape(name, T_cell_element, bvh, hull if hull is not None else bvh, hull is None)


def _is_convex(mesh: Mesh, hull: Any) -> bool:
    """Closed and enclosing its hull's volume: then the mesh is its hull (to rounding)."""
    full = float(hull.computeVolume())
    return mesh.is_watertight and abs(mesh.volume - full) <= CONVEX_VOLUME * full


def _bvh(mesh: Mesh) -> Any:
    bvh = coal.BVHModelOBBRSS()
    bvh.beginModel(len(mesh.faces), len(mesh.vertices))
    bvh.addVertices(mesh.vertices)
    bvh.addTriangles(mesh.faces)
    bvh.endModel()
    return bvh


def _convex(mesh: Mesh) -> Any | None:
    try:
        return convex_hull(mesh.vertices)  # None for a flat mesh
    except Exception:  # qhull on degenerate input
        return None


def _enclosure_notes(cell: CellModel, statics: Sequence[StaticShape]) -> list[str]:
    """Mesh elements thick enough to hold a moving shape wholly inside (which a BVH misses)."""
    thinnest = min(
        (_min_width(o.geometry) for o in cell.collision.geometryObjects), default=math.inf
    )
    out = []
    for s in statics:
        if isinstance(s.shape, coal.BVHModelBase):
            s.shape.computeLocalAABB()
            extent = np.asarray(s.shape.aabb_local.max_) - np.asarray(s.shape.aabb_local.min_)
            if float(extent.min()) >= thinnest:
                out.append(
                    f"element '{s.name}': its mesh's box is {float(extent.min()) * 1000:.0f} mm "
                    f"at its thinnest, room for a {thinnest * 1000:.0f} mm link if its walls "
                    "are that thick: a shape wholly inside a mesh is not seen (a BVH is a surface)"
                )
    return out


def _min_width(shape: Any) -> float:
    if isinstance(shape, coal.Capsule | coal.Sphere | coal.Cylinder):
        return 2.0 * float(shape.radius)
    if isinstance(shape, coal.Box):
        return 2.0 * float(np.min(shape.halfSide))
    shape.computeLocalAABB()
    return float(np.min(np.asarray(shape.aabb_local.max_) - np.asarray(shape.aabb_local.min_)))


# ---------------------------------------------------------------------------------- SRDF


def srdf_of(world: World) -> dict[str, frozenset[Pair]]:
    """The SRDF pairs of each robot whose cell.yaml entry names an ``srdf`` file."""
    root = world.cell_file.parent
    return {
        name: load_srdf(resolve_inside(root, robot.srdf, world.cell_file))
        for name, robot in world.cell.robots.items()
        if robot.srdf is not None
    }


def load_srdf(path: Path) -> frozenset[Pair]:
    """The ``<disable_collisions link1= link2= reason=/>`` pairs of an SRDF, as link names."""
    root = parse_xml(path, "xml").getroot()
    out = set()
    for el in root.iter("disable_collisions"):
        a, b = el.get("link1"), el.get("link2")
        if not a or not b:
            raise InputError.at("<disable_collisions> needs link1 and link2", path, el.sourceline)
        out.add(pair_key(a, b))
    return frozenset(out)


def _srdf_reasons(
    robot: str, pairs: Iterable[Pair], names: Sequence[str], notes: list[str]
) -> dict[Pair, str]:
    """An SRDF names links; a link may have several objects (``link#2``) or none."""
    by_link: dict[str, list[str]] = {}
    for n in names:
        owner, _, rest = n.partition("/")
        if owner == robot:
            # every solid of the tool ('tool', 'tool/finger_left') is the link 'tool'
            by_link.setdefault(rest.split("#", 1)[0].split("/", 1)[0], []).append(n)
    out: dict[Pair, str] = {}
    for a, b in pairs:
        if a not in by_link or b not in by_link:
            missing = a if a not in by_link else b
            notes.append(f"SRDF of '{robot}': link '{missing}' has no collision geometry")
            continue
        for x in by_link[a]:
            for y in by_link[b]:
                if x != y:
                    out[pair_key(x, y)] = "srdf"
    return out


# ---------------------------------------------------------------------------------- bounds


def _chain(parents: Sequence[int], joint: int) -> list[int]:
    """The joints from the root to ``joint``, root first (empty for joint 0)."""
    out = []
    while joint != 0:
        out.append(joint)
        joint = parents[joint]
    return out[::-1]


def _joint_axes(model: Any) -> tuple[Vec, list[bool]]:
    """Each joint's axis in its own frame, and whether it is prismatic (from the Jacobian at
    the neutral configuration, so any revolute or prismatic joint type works)."""
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    axes, prismatic = np.zeros((model.njoints, 3)), [False] * model.njoints
    for j in range(1, model.njoints):
        # (6, nv): pinocchio hands a one-joint model's 6x1 Jacobian back as a 1-D array
        J = np.reshape(pin.getJointJacobian(model, data, j, pin.ReferenceFrame.LOCAL), (6, -1))
        col = J[:, model.joints[j].idx_v]
        prismatic[j] = bool(np.linalg.norm(col[3:]) < 1e-12)
        axes[j] = col[:3] if prismatic[j] else col[3:]
    return axes, prismatic


def _travel(model: Any, j: int) -> float:
    i = model.joints[j].idx_q
    return float(max(abs(model.lowerPositionLimit[i]), abs(model.upperPositionLimit[i])))


def _local_sphere(model_geometry: Any, i: int) -> tuple[Vec, float]:
    """Centre (in the parent joint's frame) and radius of a sphere holding object i."""
    obj = model_geometry.geometryObjects[i]
    shape = obj.geometry
    centre = obj.placement.act(np.asarray(shape.aabb_center, dtype=float))
    return np.asarray(centre), float(shape.aabb_radius)


def _motion_radii(
    model: Any, geometry: Any, objects: Sequence[SceneObject]
) -> tuple[Vec, NDArray[np.bool_]]:
    """radii[o, q_j]: how far (m) any point of object o moves per unit motion of joint j (per
    rad: its distance from j's axis, bounded by its distance from j's origin through the chain's
    fixed offsets; per m for a prismatic joint: 1); chains[o, q_j]: j moves o."""
    assert model.nq == model.nv, "one coordinate per joint"
    parents = [int(p) for p in model.parents]
    axes, prismatic = _joint_axes(model)
    radii = np.zeros((len(objects), model.nq))
    chains = np.zeros((len(objects), model.nq), dtype=bool)
    for o, obj in enumerate(objects):
        chain = _chain(parents, obj.joint)
        centre, rho = _local_sphere(geometry, o)
        reach = float(np.linalg.norm(centre)) + rho  # from the origin of the object's joint
        for j in reversed(chain):
            q = model.joints[j].idx_q
            chains[o, q] = True
            if prismatic[j]:
                radii[o, q] = 1.0
            elif j == obj.joint:  # rigid in j's frame: its distance from the axis
                a = axes[j]
                radii[o, q] = float(np.linalg.norm(centre - a * float(a @ centre))) + rho
            else:
                radii[o, q] = reach
            # moving to the parent joint's origin: the fixed offset, plus j's own travel
            reach += float(np.linalg.norm(model.jointPlacements[j].translation))
            if prismatic[j]:
                reach += _travel(model, j)
    return radii, chains


def _pair_motion(
    radii: Vec, chains: NDArray[np.bool_], pairs: Sequence[tuple[int, int]], nq: int
) -> Vec:
    """(P, nq): joints moving both objects of a pair move them together (no relative motion);
    a joint moving one of them moves it by its radius."""
    out = np.zeros((len(pairs), nq))
    for p, (a, b) in enumerate(pairs):
        only_a, only_b = chains[a] & ~chains[b], chains[b] & ~chains[a]
        out[p] = np.where(only_a, radii[a], 0.0) + np.where(only_b, radii[b], 0.0)
    return out


def _reach(model: Any, geometry: Any, objects: Sequence[SceneObject]) -> tuple[Vec, Vec]:
    """A sphere (cell frame) each object stays inside at every configuration: about the fixed
    origin of its chain's first joint, radius the chain's offsets and travels plus its own."""
    parents = [int(p) for p in model.parents]
    _, prismatic = _joint_axes(model)
    data = model.createData()
    gdata = pin.GeometryData(geometry)
    pin.updateGeometryPlacements(model, data, geometry, gdata, pin.neutral(model))
    centres, radii = np.zeros((len(objects), 3)), np.zeros(len(objects))
    for o, obj in enumerate(objects):
        centre, rho = _local_sphere(geometry, o)
        chain = _chain(parents, obj.joint)
        if not chain:  # fixed: where it is
            centres[o] = gdata.oMg[o].act(
                np.asarray(geometry.geometryObjects[o].geometry.aabb_center)
            )
            radii[o] = rho
            continue
        radius = float(np.linalg.norm(centre)) + rho
        for j in chain[1:]:
            radius += float(np.linalg.norm(model.jointPlacements[j].translation))
        radius += sum(_travel(model, j) for j in chain if prismatic[j])
        # the root joint's frame before its own motion is fixed in the cell
        centres[o] = model.jointPlacements[chain[0]].translation
        radii[o] = radius
    return centres, radii


# ---------------------------------------------------------------------------------- sampling


# (arm signature, samples, margin, seed) -> ((link-local names), closest distance)
SelfPairMemo = dict[tuple[str, int, float, int], tuple[tuple[Pair, float], ...]]


def sampled_self_pairs(
    arm: Arm,
    samples: int = ACM_SAMPLES,
    margin: float = ACM_MARGIN,
    seed: int = ACM_SEED,
    memo: SelfPairMemo | None = None,
) -> dict[Pair, float]:
    """One arm's pairs (links, tool) that never came within ``margin`` in ``samples`` random
    configurations within its limits (MoveIt's 'never in collision'), with the closest
    distance seen. Seeded and deterministic. ``memo``: results by arm geometry relative to
    its base, so the second of two identical arms costs nothing."""
    memo = {} if memo is None else memo
    key = (_arm_signature(arm), samples, margin, seed)
    if key not in memo:
        memo[key] = _sample_self_pairs(arm, samples, margin, seed)
    prefix = f"{arm.name}/"
    return {pair_key(prefix + a, prefix + b): d for (a, b), d in memo[key]}


def _sample_self_pairs(
    arm: Arm, samples: int, margin: float, seed: int
) -> tuple[tuple[Pair, float], ...]:
    model, geometry = arm.model, _swept_fingers(arm)
    geometry.removeAllCollisionPairs()
    parents = [int(p) for p in model.parents]
    names = [str(o.name).split("/", 1)[1] for o in geometry.geometryObjects]
    joints = [int(o.parentJoint) for o in geometry.geometryObjects]
    candidates = [
        (i, j)
        for i in range(len(names))
        for j in range(i + 1, len(names))
        if joints[i] != joints[j]
        and parents[joints[i]] != joints[j]
        and parents[joints[j]] != joints[i]
    ]
    for i, j in candidates:
        geometry.addCollisionPair(pin.CollisionPair(i, j))
    rng = np.random.default_rng(seed)
    Q = rng.uniform(arm.limits.lower, arm.limits.upper, (samples, arm.nq))
    never = _never_within(model, geometry, Q, margin)
    # Random samples are sparse in 6-D: from each surviving pair's closest samples, descend
    # its distance to a local minimum, and keep checking any pair that then comes too close.
    starts = Q[: min(len(Q), CLOSEST_SAMPLES)]
    closest = _closest(model, geometry, starts, never, arm.limits.lower, arm.limits.upper)
    return tuple(
        (pair_key(names[candidates[p][0]], names[candidates[p][1]]), closest[p])
        for p in never
        if closest[p] > margin
    )


def _swept_fingers(arm: Arm) -> Any:
    """A copy of the arm's geometry with each finger as the box of its travel over the jaw's
    openings: a pair never near it is never near the finger at any opening."""
    geometry = arm.collision.copy()
    if arm.fingers is None:
        return geometry
    (T_left, T_right), size = arm.fingers.swept()
    T_joint_flange = arm.model.frames[arm.tool0].placement
    for name, T in zip(arm.fingers.names, (T_left, T_right), strict=True):
        obj = geometry.geometryObjects[geometry.getGeometryId(f"{arm.name}/{name}")]
        obj.placement = T_joint_flange * pin.SE3(T)
        obj.geometry = coal.Box(*size)
    return geometry


def _arm_signature(arm: Arm) -> str:
    """A hash of what the self pairs depend on: shapes, joints and limits, all relative to the
    arm's base (the base pose moves every object of the arm together)."""
    T_base_cell = pin.SE3(arm.T_cell_base).inverse()
    h = hashlib.sha256()

    def add(M: Any) -> None:
        h.update(np.asarray(M.homogeneous).round(12).tobytes())

    for obj in _swept_fingers(arm).geometryObjects:
        shape = obj.geometry
        shape.computeLocalAABB()
        h.update(
            f"{str(obj.name).split('/', 1)[1]}|{obj.parentJoint}|{type(shape).__name__}".encode()
        )
        add(T_base_cell * obj.placement if obj.parentJoint == 0 else obj.placement)
        h.update(np.asarray(shape.aabb_local.min_).round(12).tobytes())
        h.update(np.asarray(shape.aabb_local.max_).round(12).tobytes())
    for j in range(1, arm.model.njoints):
        placement = arm.model.jointPlacements[j]
        add(T_base_cell * placement if arm.model.parents[j] == 0 else placement)
    h.update(np.concatenate([arm.limits.lower, arm.limits.upper]).tobytes())
    return h.hexdigest()


def _never_within(model: Any, geometry: Any, Q: Vec, margin: float) -> list[int]:
    """Pairs of ``geometry`` never within ``margin`` at any row of Q. A collision query with
    that security margin stops at the first pair within it; that pair is then switched off and
    the same state checked again, so each state costs one C++ call once the pairs that do come
    close have been found."""
    data, gdata = model.createData(), pin.GeometryData(geometry)
    for request in gdata.collisionRequests:
        request.security_margin = margin
    active = list(range(len(geometry.collisionPairs)))
    for q in Q:
        while active and pin.computeCollisions(model, data, geometry, gdata, q, True):
            # pairs before the hit were computed just now and are free: the first active pair
            # reporting a collision is the hit (inactive pairs keep stale results)
            hit = next(p for p in active if gdata.collisionResults[p].isCollision())
            gdata.deactivateCollisionPair(hit)
            active.remove(hit)
    return active


CLOSEST_SAMPLES = 2000  # samples whose closest approach seeds the descent
REFINE_STARTS = 3  # closest samples each pair's local descent starts from
REFINE_ITERATIONS = 60


def _closest(
    model: Any, geometry: Any, Q: Vec, pairs: Sequence[int], lower: Vec, upper: Vec
) -> dict[int, float]:
    """Each pair's closest approach: the minimum over Q, then lowered by projected gradient
    descent (the gradient from coal's witness points and the joint Jacobians) from the
    REFINE_STARTS closest samples."""
    if not pairs:
        return {}
    data, gdata = model.createData(), pin.GeometryData(geometry)
    sampled = np.empty((len(Q), len(pairs)))
    for s, q in enumerate(Q):
        pin.updateGeometryPlacements(model, data, geometry, gdata, q)
        for k, p in enumerate(pairs):
            sampled[s, k] = pin.computeDistance(geometry, gdata, p).min_distance
    out = {}
    for k, p in enumerate(pairs):
        best = float(sampled[:, k].min())
        for s in np.argsort(sampled[:, k], kind="stable")[:REFINE_STARTS]:
            d = _descend(model, data, geometry, gdata, p, Q[s], lower, upper)
            best = min(best, d)
        out[p] = best
    return out


def _descend(
    model: Any, data: Any, geometry: Any, gdata: Any, p: int, q: Vec, lower: Vec, upper: Vec
) -> float:
    """Pair p's distance, minimised from q by gradient steps within the limits (step length
    halved whenever a step does not lower it)."""
    q = q.copy()
    d, grad = _distance_gradient(model, data, geometry, gdata, p, q)
    step = 0.05  # rad per step along the normalised gradient at first
    for _ in range(REFINE_ITERATIONS):
        norm = float(np.linalg.norm(grad))
        if norm < 1e-12 or step < 1e-5:
            break
        trial = np.clip(q - step * grad / norm, lower, upper)
        d_trial, g_trial = _distance_gradient(model, data, geometry, gdata, p, trial)
        if d_trial < d:
            q, d, grad = trial, d_trial, g_trial
            step *= 1.5
        else:
            step *= 0.5
    return d


def _distance_gradient(
    model: Any, data: Any, geometry: Any, gdata: Any, p: int, q: Vec
) -> tuple[float, Vec]:
    """Pair p's distance at q and its gradient: the witness points' relative velocity along
    the normal, per unit joint velocity."""
    pin.computeJointJacobians(model, data, q)
    pin.updateGeometryPlacements(model, data, geometry, gdata)
    result = pin.computeDistance(geometry, gdata, p)
    pair = geometry.collisionPairs[p]
    points = (np.asarray(result.getNearestPoint1()), np.asarray(result.getNearestPoint2()))
    offset = points[1] - points[0]
    length = float(np.linalg.norm(offset))
    if length < 1e-12:
        return float(result.min_distance), np.zeros(model.nv)
    normal = offset / length
    velocity = np.zeros((2, model.nv))
    for side, g_id in enumerate((pair.first, pair.second)):
        joint = int(geometry.geometryObjects[g_id].parentJoint)
        if joint == 0:
            continue
        J = pin.getJointJacobian(model, data, joint, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        J = np.reshape(J, (6, -1))  # 1-D for a one-joint model
        lever = points[side] - data.oMi[joint].translation
        velocity[side] = normal @ (J[:3] - g.skew(lever) @ J[3:])
    return float(result.min_distance), velocity[1] - velocity[0]


def sampled_first_joint_pairs(
    cell: CellModel, statics: Sequence[StaticShape], margin: float = ACM_MARGIN
) -> set[Pair]:
    """Objects moved by an arm's first joint only, against the environment: one coordinate,
    so sweep it at steps that move no point more than margin/2; a pair never within ``margin``
    at a step is then never closer than margin/2 anywhere (a proof, not a sample)."""
    model = cell.model
    parents = [int(p) for p in model.parents]
    objects = _objects_of(cell)
    geometry = pin.GeometryModel()
    for obj in cell.collision.geometryObjects:
        geometry.addGeometryObject(obj)
    first = [i for i, o in enumerate(objects) if o.joint and parents[o.joint] == 0]
    base = len(objects)
    for s in statics:
        geometry.addGeometryObject(
            pin.GeometryObject(s.name, 0, 0, pin.SE3(s.T_cell_shape), s.bound)
        )
    for i in range(geometry.ngeoms):
        geometry.geometryObjects[i].geometry.computeLocalAABB()
    pairs = [(i, base + k) for i in first for k in range(len(statics))]
    for i, k in pairs:
        geometry.addCollisionPair(pin.CollisionPair(i, k))
    if not pairs:
        return set()
    radii, _ = _motion_radii(model, geometry, objects)  # the arms' objects come first
    out: set[Pair] = set()
    for joint in sorted({objects[i].joint for i in first}):
        q_j = model.joints[joint].idx_q
        mine = [p for p, (i, _) in enumerate(pairs) if objects[i].joint == joint]
        step = margin / 2 / max(float(radii[i, q_j]) for i in first if objects[i].joint == joint)
        lo, hi = model.lowerPositionLimit[q_j], model.upperPositionLimit[q_j]
        Q = np.tile(pin.neutral(model), (math.ceil((hi - lo) / step) + 1, 1))
        Q[:, q_j] = np.linspace(lo, hi, len(Q))
        sub = geometry.copy()
        sub.removeAllCollisionPairs()
        for p in mine:
            sub.addCollisionPair(pin.CollisionPair(*pairs[p]))
        for p in _never_within(model, sub, Q, margin):
            i, k = pairs[mine[p]]
            out.add(pair_key(objects[i].name, statics[k - base].name))
    return out
