"""Reading an untrusted URDF and turning it into a pinocchio model and collision geometry.

The file is parsed with :mod:`cellengine.info.xmlsafe` (no DTD, no entities, no network),
checked here, and rewritten as a minimal URDF: links with their inertials, and joints. That
rewritten text is the only thing pinocchio parses, so no file name, DTD or unknown element of
the user's file ever reaches it.

Collision geometry is built here rather than by pinocchio, so that every file reference is
resolved by our code inside the cell folder:

- ``<box>`` becomes ``coal.Box``, ``<sphere>`` ``coal.Sphere``;
- ``<cylinder>`` becomes ``coal.Capsule`` of the same radius and length: URDF has no capsule,
  capsules are the cheapest shape to check, and a capsule covers its cylinder (it adds a
  half-sphere of the radius at each end), so the substitution never misses a collision;
- ``<mesh>`` becomes the ``coal.Convex`` hull of the mesh (read through trimesh, scaled; the
  hull by coal's qhull). ``package://pkg/path`` is looked up in the URDF's own folder and its
  parents up to the cell folder (a folder named ``pkg``, or one holding ``pkg``); other paths
  are relative to the URDF. Anything resolving outside the cell folder is refused.

``<visual>`` elements are ignored (never read). Joints: revolute, continuous, prismatic and
fixed. A continuous joint becomes a revolute joint limited to +-2 pi, so that every joint has
one coordinate (pinocchio would give it two, cos and sin) and a trajectory has one position per
joint. Movable joints off the arm's chain (root to tip), e.g. a gripper's fingers, are locked
at 0 (or the limit nearest 0) and written as fixed joints.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from lxml import etree

from cellengine import geometry as g
from cellengine.arrays import Mat
from cellengine.errors import InputError, known
from cellengine.info.bounds import MAX_COORDINATE, SCALES, scale_ok
from cellengine.info.files import read_capped, real, resolve_inside
from cellengine.info.xmlsafe import parse_xml
from cellengine.motion.hull import convex_hull

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed")
MOVABLE = ("revolute", "continuous", "prismatic")
CONTINUOUS_LIMIT = 2.0 * math.pi
MESH_FORMATS = ("stl", "obj", "ply", "off", "glb")  # self-contained formats trimesh reads
PACKAGE = "package://"
# A URL scheme (file:, http:, ...); one letter and a slash is a Windows drive, not a scheme.
_URL = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]+:")

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Joint:
    name: str
    type: str  # one of JOINT_TYPES, as written
    parent: str
    child: str
    xyz: Vec3
    rpy: Vec3
    axis: Vec3  # unit vector
    lower: float | None
    upper: float | None
    velocity: float | None
    effort: float | None
    mimic: bool
    line: int | None

    @property
    def movable(self) -> bool:
        return self.type in MOVABLE

    def T_parent_child(self, q: float = 0.0) -> Mat:
        """The child link's frame in the parent link's at joint value ``q``."""
        T_parent_joint = g.pose(self.xyz, self.rpy)
        if q == 0.0 or not self.movable:
            return T_parent_joint
        if self.type == "prismatic":
            return T_parent_joint @ g.transform(t=np.multiply(self.axis, q))
        return T_parent_joint @ g.transform(g.axis_angle_to_matrix(self.axis, q))


@dataclass(frozen=True)
class Inertial:
    xyz: Vec3
    rpy: Vec3
    mass: float
    inertia: tuple[float, float, float, float, float, float]  # ixx ixy ixz iyy iyz izz


@dataclass(frozen=True)
class Collision:
    link: str
    T_link_shape: Mat
    shape: Any  # a coal.CollisionGeometry
    kind: str  # box | sphere | capsule | convex
    mesh: Path | None
    line: int | None


@dataclass(frozen=True)
class Urdf:
    """A checked URDF: a tree of links and joints, with its collision shapes built."""

    file: Path
    name: str
    root: str
    links: Mapping[str, Inertial | None]  # in file order
    joints: Mapping[str, Joint]  # in file order
    collisions: tuple[Collision, ...]

    def parent_joint(self, link: str) -> Joint | None:
        return next((j for j in self.joints.values() if j.child == link), None)

    def chain(self, tip: str) -> list[Joint]:
        """Every joint from the root to ``tip``, root first."""
        out: list[Joint] = []
        joint = self.parent_joint(tip)
        while joint is not None:
            out.append(joint)
            joint = self.parent_joint(joint.parent)
        return out[::-1]


# ---------------------------------------------------------------------------------- reading


def read_urdf(path: Path, cell_dir: Path) -> Urdf:
    """Parse and check ``path``; mesh references must resolve inside ``cell_dir``."""
    root_el = parse_xml(path, "urdf").getroot()
    if etree.QName(root_el).localname != "robot":
        raise InputError.at(
            f"a URDF's root element must be <robot>, not <{root_el.tag}>", path, root_el.sourceline
        )
    reader = _Reader(path, cell_dir)
    links: dict[str, Inertial | None] = {}
    joints: dict[str, Joint] = {}
    collisions: list[Collision] = []
    for el in root_el:
        if not isinstance(el.tag, str):  # comments, processing instructions
            continue
        tag = etree.QName(el).localname
        if tag == "link":
            name = reader.name(el, "link", links)
            links[name] = reader.inertial(el, name)
            collisions += reader.collisions(el, name)
        elif tag == "joint":
            joint = reader.joint(el, joints)
            joints[joint.name] = joint
    root = _check_tree(path, links, joints)
    return Urdf(
        path,
        str(root_el.get("name") or path.stem),
        root,
        MappingProxyType(links),
        MappingProxyType(joints),
        tuple(collisions),
    )


def _check_tree(path: Path, links: Mapping[str, object], joints: Mapping[str, Joint]) -> str:
    """One root; every joint joins known links; every link has at most one parent; no loop."""
    if not links:
        raise InputError.at("the URDF has no links", path)
    parent_of: dict[str, Joint] = {}
    for j in joints.values():
        for role, link in (("parent", j.parent), ("child", j.child)):
            if link not in links:
                raise InputError.at(
                    f"joint '{j.name}': unknown {role} link '{link}'" + known(links), path, j.line
                )
        if j.child in parent_of:
            raise InputError.at(
                f"joint '{j.name}': link '{j.child}' already has parent joint "
                f"'{parent_of[j.child].name}'; a URDF is a tree",
                path,
                j.line,
            )
        parent_of[j.child] = j
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        what = ", ".join(f"'{r}'" for r in roots) if roots else "none (the joints form a loop)"
        raise InputError.at(f"a URDF needs exactly one root link; found {what}", path)
    for link in links:  # walk up from every link: a loop never reaches the root
        seen: set[str] = set()
        while link in parent_of:
            if link in seen:
                raise InputError.at(
                    f"joints form a loop through link '{link}'", path, parent_of[link].line
                )
            seen.add(link)
            link = parent_of[link].parent
    return roots[0]


class _Reader:
    """Element readers; every failure names the URDF file and line."""

    def __init__(self, path: Path, cell_dir: Path) -> None:
        self.path = path
        self.cell_dir = cell_dir

    def fail(self, message: str, el: Any) -> InputError:
        return InputError.at(message, self.path, el.sourceline)

    def name(self, el: Any, kind: str, seen: Mapping[str, object]) -> str:
        name = el.get("name")
        if not name or not name.strip():
            raise self.fail(f"a <{kind}> needs a name", el)
        if name in seen:
            raise self.fail(f"{kind} '{name}' is defined twice", el)
        return str(name)

    def floats(
        self, el: Any, attr: str, n: int, what: str, default: str | None = None
    ) -> list[float]:
        text = el.get(attr, default)
        if text is None:
            raise self.fail(f"{what}: missing '{attr}'", el)
        try:
            values = [float(x) for x in text.replace(",", " ").split()]
        except ValueError:
            values = []
        if len(values) != n or not all(math.isfinite(v) for v in values):
            count = "a number" if n == 1 else f"{n} numbers"
            raise self.fail(f"{what}: '{attr}' must be {count}, got '{text}'", el)
        return values

    def origin(self, el: Any, what: str) -> tuple[Vec3, Vec3]:
        o = _child(el, "origin")
        if o is None:
            return (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        xyz = self.floats(o, "xyz", 3, f"{what} origin", "0 0 0")
        rpy = self.floats(o, "rpy", 3, f"{what} origin", "0 0 0")
        return (xyz[0], xyz[1], xyz[2]), (rpy[0], rpy[1], rpy[2])

    def inertial(self, link_el: Any, link: str) -> Inertial | None:
        el = _child(link_el, "inertial")
        if el is None:
            return None
        what = f"link '{link}' inertial"
        xyz, rpy = self.origin(el, what)
        mass_el, inertia_el = _child(el, "mass"), _child(el, "inertia")
        mass = self.floats(mass_el, "value", 1, what)[0] if mass_el is not None else 0.0
        if mass < 0:
            raise self.fail(f"{what}: mass must not be negative, got {mass}", mass_el)
        names = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
        values = [0.0] * 6
        if inertia_el is not None:
            values = [self.floats(inertia_el, k, 1, what, "0")[0] for k in names]
        return Inertial(xyz, rpy, mass, (values[0], values[1], values[2], *values[3:]))  # type: ignore[arg-type]

    def joint(self, el: Any, seen: Mapping[str, object]) -> Joint:
        name = self.name(el, "joint", seen)
        what = f"joint '{name}'"
        kind = el.get("type")
        if kind not in JOINT_TYPES:
            raise self.fail(
                f"{what}: type '{kind}' is not supported; use one of {', '.join(JOINT_TYPES)}", el
            )
        parent, child = _child(el, "parent"), _child(el, "child")
        if parent is None or child is None or not parent.get("link") or not child.get("link"):
            raise self.fail(f"{what}: needs <parent link=...> and <child link=...>", el)
        xyz, rpy = self.origin(el, what)
        axis_el = _child(el, "axis")
        axis = self.floats(axis_el, "xyz", 3, what, "1 0 0") if axis_el is not None else [1, 0, 0]
        norm = float(np.linalg.norm(axis))
        if kind in MOVABLE and norm < 1e-9:
            raise self.fail(f"{what}: the axis must not be zero", axis_el)
        unit = [a / norm for a in axis] if norm >= 1e-9 else [1.0, 0.0, 0.0]
        limit = _child(el, "limit")

        def bound(attr: str) -> float | None:
            if limit is None or limit.get(attr) is None:
                return None
            return self.floats(limit, attr, 1, f"{what} limit")[0]

        return Joint(
            name,
            str(kind),
            str(parent.get("link")),
            str(child.get("link")),
            xyz,
            rpy,
            (unit[0], unit[1], unit[2]),
            bound("lower"),
            bound("upper"),
            bound("velocity"),
            bound("effort"),
            _child(el, "mimic") is not None,
            el.sourceline,
        )

    def collisions(self, link_el: Any, link: str) -> list[Collision]:
        out = []
        for el in link_el:
            if isinstance(el.tag, str) and etree.QName(el).localname == "collision":
                out.append(self.collision(el, link))
        return out

    def collision(self, el: Any, link: str) -> Collision:
        what = f"link '{link}' collision"
        xyz, rpy = self.origin(el, what)
        geom = _child(el, "geometry")
        shapes = [c for c in (geom if geom is not None else []) if isinstance(c.tag, str)]
        if len(shapes) != 1:
            raise self.fail(f"{what}: <geometry> must hold exactly one shape", geom or el)
        shape_el = shapes[0]
        kind = etree.QName(shape_el).localname
        T_link_shape = g.pose(xyz, rpy)
        mesh: Path | None = None
        if kind == "box":
            size = self.floats(shape_el, "size", 3, f"{what} box")
            self.positive(size, shape_el, f"{what} box size")
            shape, kind = coal.Box(*size), "box"
        elif kind == "sphere":
            (r,) = self.floats(shape_el, "radius", 1, f"{what} sphere")
            self.positive([r], shape_el, f"{what} sphere radius")
            shape = coal.Sphere(r)
        elif kind == "cylinder":
            (r,) = self.floats(shape_el, "radius", 1, f"{what} cylinder")
            (length,) = self.floats(shape_el, "length", 1, f"{what} cylinder")
            self.positive([r, length], shape_el, f"{what} cylinder radius and length")
            shape, kind = coal.Capsule(r, length), "capsule"
        elif kind == "mesh":
            ref = shape_el.get("filename")
            if not ref:
                raise self.fail(f"{what}: <mesh> needs a filename", shape_el)
            scale = self.floats(shape_el, "scale", 3, f"{what} mesh", "1 1 1")
            if not scale_ok(scale):
                raise self.fail(
                    f"{what} mesh: 'scale' must be between {SCALES[0]:g} and {SCALES[1]:g} in "
                    f"size, got '{shape_el.get('scale')}'",
                    shape_el,
                )
            mesh = resolve_mesh(ref, self.path, self.cell_dir, shape_el.sourceline)
            shape, kind = mesh_hull(mesh, ref, scale, self.path, shape_el.sourceline), "convex"
        else:
            raise self.fail(
                f"{what}: unknown shape <{kind}>; use box, sphere, cylinder or mesh", shape_el
            )
        return Collision(link, T_link_shape, shape, kind, mesh, el.sourceline)

    def positive(self, values: Sequence[float], el: Any, what: str) -> None:
        if min(values) <= 0:
            raise self.fail(f"{what} must be greater than 0", el)


def _child(el: Any, tag: str) -> Any:
    for c in el:
        if isinstance(c.tag, str) and etree.QName(c).localname == tag:
            return c
    return None


# ---------------------------------------------------------------------------------- meshes


def resolve_mesh(ref: str, urdf_file: Path, cell_dir: Path, line: int | None = None) -> Path:
    """The file a URDF mesh reference names, inside ``cell_dir``; InputError otherwise."""
    where = (urdf_file, line)
    if ref.startswith(PACKAGE):
        package, _, rest = ref[len(PACKAGE) :].partition("/")
        if not package or not rest:
            raise InputError.at(f"mesh '{ref}': write package://<package>/<path>", *where)
        candidates = _package_candidates(package, rest, urdf_file.parent, cell_dir)
    elif _URL.match(ref):
        raise InputError.at(
            f"mesh '{ref}' is a URL; use a path inside the cell folder or package://", *where
        )
    else:
        candidates = [urdf_file.parent / ref]
    base = real(cell_dir)
    for c in candidates:
        if not Path(os.path.normpath(c.absolute())).is_relative_to(base):
            raise InputError.at(f"mesh '{ref}' points outside the cell folder", *where)
    # else one that is there but no regular file (a loop of links, a FIFO): refused below
    found = next((c for c in candidates if c.is_file()), None) or next(
        (c for c in candidates if os.path.lexists(c)), None
    )
    if found is None:
        looked = ", ".join(os.path.relpath(c, base) for c in candidates)
        raise InputError.at(f"mesh '{ref}' not found (looked for {looked})", *where)
    try:  # the final word on links leading out
        return resolve_inside(base, os.path.relpath(found.absolute(), base), urdf_file, line)
    except InputError as e:
        raise InputError.at(f"mesh '{ref}': {e.problems[0].message}", *where) from None


def _package_candidates(package: str, rest: str, urdf_dir: Path, cell_dir: Path) -> list[Path]:
    """``package://package/rest``: in the URDF's folder and each parent up to the cell folder,
    the folder itself if it is named ``package``, then its sub-folder ``package``."""
    if package in (".", ".."):
        return [urdf_dir / package / rest]  # refused as outside or found, never searched
    base, folder = real(cell_dir), real(urdf_dir)
    out: list[Path] = []
    while True:
        if folder.name == package:
            out.append(folder / rest)
        out.append(folder / package / rest)
        if folder == base or not folder.is_relative_to(base):
            return out
        folder = folder.parent


def mesh_hull(path: Path, ref: str, scale: Sequence[float], urdf: Path, line: int | None) -> Any:
    """The convex hull of a mesh file (errors at ``urdf``:``line``, the file naming it)."""
    ext = path.suffix.lower().lstrip(".")
    if ext not in MESH_FORMATS:
        raise InputError.at(
            f"mesh '{ref}': unsupported format '{path.suffix}'; use "
            + ", ".join(f.upper() for f in MESH_FORMATS),
            urdf,
            line,
        )
    data = read_capped(path, "mesh", urdf, line)
    import trimesh  # here: importing it costs half a second, and only mesh files need it

    if ext == "stl" and not _stl_readable(data):  # trimesh's guess depends on what is installed
        raise InputError.at(
            f"mesh '{ref}' cannot be read: not UTF-8 text, nor a binary STL whose size matches "
            "its triangle count",
            urdf,
            line,
        )
    try:  # from bytes, so trimesh can open no other file (textures, materials)
        mesh: Any = trimesh.load(io.BytesIO(data), file_type=ext, force="mesh")
        vertices = np.asarray(mesh.vertices, dtype=float) * np.asarray(scale, dtype=float)
    except ImportError:  # text not UTF-8: trimesh guesses its encoding with a module we lack
        binary = ", nor a binary STL whose size matches its triangle count" if ext == "stl" else ""
        raise InputError.at(
            f"mesh '{ref}' cannot be read: not UTF-8 text{binary}", urdf, line
        ) from None
    except Exception as e:  # trimesh's readers raise many kinds; all mean "not a mesh"
        raise InputError.at(f"mesh '{ref}' cannot be read: {_one_line(e)}", urdf, line) from None
    if len(vertices) == 0 or len(mesh.faces) == 0:
        raise InputError.at(f"mesh '{ref}' has no triangles", urdf, line)
    if not np.abs(vertices).max() <= MAX_COORDINATE:  # NaN too
        raise InputError.at(
            f"mesh '{ref}' has points beyond {MAX_COORDINATE:g} m of its link (with its scale; "
            'a mesh in millimetres needs scale="0.001 0.001 0.001")',
            urdf,
            line,
        )
    try:
        hull = convex_hull(vertices)
    except Exception as e:  # qhull on degenerate input
        raise InputError.at(f"mesh '{ref}' cannot be used: {_one_line(e)}", urdf, line) from None
    if hull is None:
        raise InputError.at(f"mesh '{ref}' is flat: its convex hull has no volume", urdf, line)
    return hull


def _stl_readable(data: bytes) -> bool:
    """A binary STL (84-byte header and count, 50 bytes a triangle) or UTF-8 text."""
    if len(data) >= 84 and len(data) == 84 + 50 * int.from_bytes(data[80:84], "little"):
        return True
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return True


def _one_line(e: Exception) -> str:
    return " ".join(str(e).split())[:200] or type(e).__name__


# ---------------------------------------------------------------------------------- models


def lock_value(joint: Joint) -> float:
    """Where a movable joint off the arm's chain is locked: 0, or the limit nearest 0."""
    lo = joint.lower if joint.lower is not None else -math.inf
    hi = joint.upper if joint.upper is not None else math.inf
    return 0.0 if joint.type == "continuous" else float(min(max(0.0, lo), hi))


def check_chain(urdf: Urdf, tip: str) -> list[Joint]:
    """The movable joints from root to ``tip``, each with usable limits."""
    movable = [j for j in urdf.chain(tip) if j.movable]
    if not movable:
        raise InputError.at(
            f"no movable joint between the root link '{urdf.root}' and the tip '{tip}'", urdf.file
        )
    for j in movable:
        where = (urdf.file, j.line)
        if j.mimic:
            raise InputError.at(f"joint '{j.name}' mimics another; an arm's joints cannot", *where)
        if j.velocity is None or j.velocity <= 0:
            raise InputError.at(
                f"joint '{j.name}' needs <limit velocity=...> greater than 0", *where
            )
        bounded = j.lower is not None and j.upper is not None and j.lower < j.upper
        if j.type != "continuous" and not bounded:
            raise InputError.at(
                f"joint '{j.name}' needs <limit lower=... upper=...> with lower < upper",
                *where,
            )
    return movable


def kinematics_xml(urdf: Urdf, tip: str, prefix: str) -> str:
    """The URDF pinocchio parses: links (with inertials) and joints only, every name prefixed;
    movable joints off the chain to ``tip`` fixed at :func:`lock_value`; continuous joints
    revolute within +-2 pi."""
    on_chain = {j.name for j in urdf.chain(tip)}
    robot = etree.Element("robot", name=prefix + urdf.name)
    for name, inertial in urdf.links.items():
        link = etree.SubElement(robot, "link", name=prefix + name)
        if inertial is not None:
            el = etree.SubElement(link, "inertial")
            _origin(el, inertial.xyz, inertial.rpy)
            etree.SubElement(el, "mass", value=_num(inertial.mass))
            keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
            etree.SubElement(
                el, "inertia", {k: _num(v) for k, v in zip(keys, inertial.inertia, strict=True)}
            )
    for j in urdf.joints.values():
        _joint_xml(robot, j, prefix, moving=j.movable and j.name in on_chain)
    return str(etree.tostring(robot, encoding="unicode"))


def _joint_xml(robot: Any, j: Joint, prefix: str, moving: bool) -> None:
    kind = ("revolute" if j.type == "continuous" else j.type) if moving else "fixed"
    el = etree.SubElement(robot, "joint", name=prefix + j.name, type=kind)
    etree.SubElement(el, "parent", link=prefix + j.parent)
    etree.SubElement(el, "child", link=prefix + j.child)
    if moving or not j.movable:
        _origin(el, j.xyz, j.rpy)
    else:  # locked: the joint's motion at its lock value folded into the origin
        xyz, rpy = g.xyz_rpy(j.T_parent_child(lock_value(j)))
        _origin(el, tuple(xyz), tuple(rpy))
    if not moving:
        return
    etree.SubElement(el, "axis", xyz=" ".join(_num(a) for a in j.axis))
    lower, upper = (
        (-CONTINUOUS_LIMIT, CONTINUOUS_LIMIT) if j.type == "continuous" else (j.lower, j.upper)
    )
    etree.SubElement(
        el,
        "limit",
        lower=_num(lower or 0.0),
        upper=_num(upper or 0.0),
        velocity=_num(j.velocity or 0.0),
        effort=_num(j.effort or 0.0),
    )


def _origin(el: Any, xyz: Sequence[float], rpy: Sequence[float]) -> None:
    etree.SubElement(
        el, "origin", xyz=" ".join(_num(v) for v in xyz), rpy=" ".join(_num(v) for v in rpy)
    )


def _num(x: float) -> str:
    return repr(float(x))  # shortest text that reads back to the same double


def build_model(urdf: Urdf, tip: str, prefix: str) -> Any:
    """The arm's pinocchio model, root link at the universe; names prefixed."""
    check_chain(urdf, tip)
    return pin.buildModelFromXML(kinematics_xml(urdf, tip, prefix))


def build_geometry(model: Any, urdf: Urdf, prefix: str, owner: str) -> Any:
    """Each collision shape of ``urdf`` on its link's frame in ``model``; named
    ``owner/link``, then ``owner/link#2``, ... when a link has several."""
    geom = pin.GeometryModel()
    count: dict[str, int] = {}
    for c in urdf.collisions:
        frame_id = model.getFrameId(prefix + c.link, pin.FrameType.BODY)
        frame = model.frames[frame_id]
        count[c.link] = count.get(c.link, 0) + 1
        name = f"{owner}/{c.link}" + (f"#{count[c.link]}" if count[c.link] > 1 else "")
        placement = frame.placement * pin.SE3(c.T_link_shape)
        obj = pin.GeometryObject(name, frame.parentJoint, frame_id, placement, c.shape)
        if c.mesh is not None:
            obj.meshPath = str(c.mesh)
        geom.addGeometryObject(obj)
    return geom
