"""X3D (XML encoding) loader: the named frames and meshes of a CAD assembly, in metres, z-up.

A Transform is composed per ISO/IEC 19775-1 (10.4.4):
P' = T·C·R·SR·S·SR⁻¹·C⁻¹·P. A named node's frame is rigid (DESIGN 3.2): its origin is where
the full affine chain maps the node's origin, its orientation the product of the chain's
``rotation`` fields only. Scale moves children and sizes geometry; it shows up in the meshes,
which are expressed in the rigid node frame.

Input is untrusted: nothing is fetched, Inline files must lie inside the cell folder, and
DEF/USE or Inline repetition is capped so a small file cannot expand without bound.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import MappingProxyType
from typing import Literal, NamedTuple, TypeAlias

import numpy as np
from lxml import etree

from cellengine.arrays import IntArray, Mat
from cellengine.errors import CellError, InputError, Problem, display_path, known
from cellengine.geometry import axis_angle_to_matrix, inverse, rot_x, transform_points
from cellengine.info import primitives
from cellengine.info.bounds import MAX_COORDINATE, SCALES, scale_ok
from cellengine.info.files import read_capped, real, resolve_inside
from cellengine.info.mesh import Mesh
from cellengine.info.xmlsafe import parse_xml

Element: TypeAlias = etree._Element

MAX_INLINE_DEPTH = 8
MAX_NESTING = 200  # keeps recursion far below Python's limit, even through Inlines
MAX_VISITS = 1_000_000  # elements visited, counting every USE instance
# Inline instances in one load. A CAD export inlines a part file once per placement: a few
# hundred. 1000 Inlines of a file of 1000 Inlines is a file built to expand, refused here
# rather than after minutes of walking a million copies.
MAX_INLINES = 10_000
MAX_TRIANGLES = 5_000_000  # and as many vertices, counting every USE instance

GROUPS = ("Anchor", "Collision", "Group", "StaticGroup", "Switch", "Transform")
GEOMETRY = (
    "Box",
    "Cone",
    "Cylinder",
    "IndexedFaceSet",
    "IndexedTriangleSet",
    "Sphere",
    "TriangleSet",
)
# Geometry without a surface (FreeCAD exports edges and vertices): nothing to collide with.
NO_SURFACE = ("IndexedLineSet", "LineSet", "PointSet")
COORDINATES = ("Coordinate", "CoordinateDouble")
_KNOWN = (*GROUPS, *GEOMETRY, *NO_SURFACE, *COORDINATES, "Shape", "Inline", "Scene", "X3D")
_CANON = {t.lower(): t for t in _KNOWN}  # FreeCAD writes <x3d> and <scene>
_CONTENT = frozenset((*GROUPS, "Shape", "Inline"))

_URL = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")
_DRIVE = re.compile(r"^[A-Za-z]:[\\/]")
_QUOTED = re.compile(r'"((?:[^"\\]|\\.)*)"')
# Markup starting with '<'; group 1 matches (empty) for a start tag and only for one.
_MARKUP = re.compile(rb"<(?:!--.*?-->|!\[CDATA\[.*?\]\]>|\?.*?\?>|[!/]|())", re.S)


def _affine(L: Mat, t: Mat) -> Mat:
    T = np.eye(4)
    T[:3, :3] = L
    T[:3, 3] = t
    return T


_ZERO3 = np.zeros(3)
_EYE3 = np.eye(3)
_EYE3.setflags(write=False)
_ONE3 = np.ones(3)
_NO_ROTATION = np.array([0.0, 0.0, 1.0, 0.0])
_Y_UP = _affine(rot_x(np.pi / 2), _ZERO3)  # T_platform_scene: x3d y (up) -> z, z -> -y
_Z_TO_Y = _affine(rot_x(-np.pi / 2), _ZERO3)  # round primitives are built along z, X3D's on y
_QUAD = np.array([[0, 1, 2], [0, 2, 3]])  # a quad's fan
_SECTIONS = 32  # around cylinders and cones: a multiple of 4, so extents are exact


@dataclass(frozen=True)
class X3DNode:
    name: str  # its DEF (or `id`, as FreeCAD writes)
    file: str  # the file it was defined in (an Inline'd file for inlined nodes)
    line: int  # source line of its element
    T_scene_node: Mat  # 4x4 rigid transform, metres, in the z-up platform frame
    mesh: Mesh | None  # this node's own geometry, in the node frame, metres
    # with bad_geometry="skip": why this node's geometry was dropped (mesh is then None)
    mesh_problem: Problem | None = None


@dataclass(frozen=True)
class X3DScene:
    file: str
    nodes: Mapping[str, X3DNode]  # every DEF'd/id'd Transform or Group, document order
    mesh: Mesh | None = None  # geometry under no named node, in the platform frame

    def node(self, name: str, file: Path, row: int) -> X3DNode:
        """The node a mapping file names at ``row``; an InputError there if there is none."""
        found = self.nodes.get(name)
        if found is None:
            raise InputError.at(
                f"unknown CAD name '{name}' (no DEF of that name in "
                f"{Path(self.file).name}){known(self.nodes)}",
                file,
                row,
            )
        return found


def load_x3d(
    path: Path,
    root: Path,
    up: Literal["y", "z"] = "y",
    *,
    meshes: bool = True,
    bad_geometry: Literal["error", "skip"] = "error",
) -> X3DScene:
    """Load ``path``; Inline urls must resolve inside ``root`` (the cell folder).

    ``up="y"`` (X3D's convention) turns the scene +90° about x into the z-up platform
    frame; ``up="z"`` leaves it as it is. ``meshes=False`` reads poses only: geometry is
    neither parsed nor checked, so a damaged mesh cannot stop the poses from loading.
    ``bad_geometry="skip"`` drops the geometry of a node whose mesh is malformed and says why
    in ``X3DNode.mesh_problem``; for formats whose collision model lies elsewhere.
    """
    if up not in ("y", "z"):
        raise ValueError(f"up must be 'y' or 'z', got {up!r}")
    loader = _Loader(real(Path(root)), meshes, bad_geometry == "skip")
    top, scene = loader.open(Path(path))
    T = _Y_UP if up == "y" else np.eye(4)
    ctx = _Ctx(top, T, T[:3, :3].copy(), None, False, 0, (top.real,))
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is checked, and refused
        for child in _children(scene):
            loader.visit(child, ctx)
    nodes = {o.name: o.node() for o in loader.owners.values()}
    return X3DScene(str(path), MappingProxyType(nodes), _mesh(loader.loose.parts))


# --- files -----------------------------------------------------------------------------------


class _File:
    """One parsed X3D file: its DEF/id names and the true lines of its elements.

    libxml2 reports an element at the line where its start tag ends, and Blender spreads a
    start tag over several lines; so lines come from the text: the k-th element in document
    order is the k-th start tag.
    """

    def __init__(self, path: Path, root: Element) -> None:
        self.name = str(path)  # as reported in errors and in X3DNode.file
        self.path = path
        self.real = real(path)  # Inline urls are relative to it; the key of the parsed files
        self.defs: dict[str, Element] = {}  # DEF and id names; a USE looks only in its file
        self._order = {el: i for i, el in enumerate(root.iter(etree.Element))}
        self._lines: IntArray | None = None
        self._cols: IntArray = np.zeros(0, dtype=np.int64)
        for el in self._order:
            self._define(el)

    def _define(self, el: Element) -> None:
        for attr in ("DEF", "id"):
            name = el.get(attr)
            if not name:
                continue
            first = self.defs.setdefault(name, el)
            if first is not el:
                where = f"{display_path(self.name)}:{self.line(first)}"
                raise self.error(el, f"duplicate name '{name}' (first defined at {where})")

    def line(self, el: Element) -> int:
        return self.position(el)[0]

    def position(self, el: Element) -> tuple[int, int | None]:
        """(line, column) where the element's start tag begins."""
        if self._lines is None:
            data = read_capped(self.path, "x3d")
            starts = np.array([m.start() for m in _MARKUP.finditer(data) if m.group(1) is not None])
            newlines = np.flatnonzero(np.frombuffer(data, np.uint8) == ord("\n"))
            before = np.searchsorted(newlines, starts)  # newlines before each start tag
            # where each line starts: 0, then after each newline (a one-line file has none)
            line_start = np.concatenate(([0], newlines + 1))[before]
            self._lines = before + 1
            self._cols = starts - line_start + 1  # in bytes: exact for ASCII, as CAD writes
        i = self._order.get(el)
        if i is None or len(self._lines) != len(self._order):  # changed since it was parsed
            return int(el.sourceline or 0), None
        return int(self._lines[i]), int(self._cols[i])

    def error(self, el: Element, message: str) -> CellError:
        return InputError.at(message, self.name, *self.position(el))


# --- traversal -------------------------------------------------------------------------------


@dataclass
class _Owner:
    """A named node collecting the geometry of the shapes it owns."""

    name: str
    file: str
    line: int
    T: Mat  # rigid platform <- node
    T_inv: Mat
    parts: list[tuple[Mat, IntArray]] = field(default_factory=list)
    problem: Problem | None = None  # the first malformed geometry, when skipped

    def node(self) -> X3DNode:
        T = self.T.copy()
        T.setflags(write=False)
        mesh = None if self.problem else _mesh(self.parts)  # never half a mesh
        return X3DNode(self.name, self.file, self.line, T, mesh, self.problem)


class _Ctx(NamedTuple):
    file: _File
    A: Mat  # affine platform <- current element (the full chain, scale included)
    R: Mat  # product of the chain's rotations: the orientation of a rigid frame here
    owner: _Owner | None  # nearest named ancestor
    instancing: bool  # inside a USE: geometry again, but no new names
    depth: int
    chain: tuple[Path, ...]  # the Inline chain of files down to this one, resolved


class _Loader:
    def __init__(self, root: Path, meshes: bool, skip_bad: bool = False) -> None:
        self.root = root
        self.meshes = meshes
        self.skip_bad = skip_bad
        self.owners: dict[str, _Owner] = {}
        self.loose = _Owner("", "", 0, np.eye(4), np.eye(4))
        self.active: set[Element] = set()  # elements being visited: USE cycles
        self.cache: dict[Element, tuple[Mat, IntArray]] = {}  # geometry, in its own frame
        self.points: dict[Element, Mat] = {}  # Coordinate nodes, often USE'd
        self.files: dict[Path, tuple[_File, Element]] = {}  # by resolved path
        self.targets: dict[Element, Path] = {}  # each Inline's file, found once
        self.visits = 0
        self.inlines = 0
        self.triangles = 0
        self.vertices = 0

    def open(self, path: Path) -> tuple[_File, Element]:
        """The file and its Scene element, parsed once however often it is Inlined."""
        key = real(path)
        if key not in self.files:
            self.files[key] = self._parse(path)
        return self.files[key]

    def _parse(self, path: Path) -> tuple[_File, Element]:
        root = parse_xml(path, kind="x3d").getroot()
        f = _File(path, root)
        if _tag(root) != "X3D":
            raise f.error(root, f"the root element must be X3D, got '{root.tag}'")
        scene = next((c for c in root if _tag(c) == "Scene"), None)
        if scene is None:
            raise f.error(root, "X3D has no Scene element")
        return f, scene

    def visit(self, el: Element, ctx: _Ctx) -> None:
        tag = _tag(el)
        if tag is None:
            return
        self._count(el, ctx)
        use = el.get("USE")
        if use is not None:
            el = self._use(el, tag, use, ctx.file)
            ctx = ctx._replace(instancing=True)
        if tag in _CONTENT:
            self.active.add(el)
            try:
                self._dispatch(el, tag, ctx._replace(depth=ctx.depth + 1))
            finally:
                self.active.discard(el)
        elif any(_tag(d) in _CONTENT for d in el.iter(etree.Element)):
            raise ctx.file.error(
                el,
                f"unsupported node '{tag}' around geometry; supported grouping nodes: "
                + ", ".join(GROUPS),
            )
        # anything else (Viewpoint, lights, Background, ...) has no geometry: ignored

    def _dispatch(self, el: Element, tag: str, ctx: _Ctx) -> None:
        if tag == "Shape":
            if self.meshes:
                self._shape(el, ctx)
        elif tag == "Inline":
            self._inline(el, ctx)
        else:
            self._group(el, tag, ctx)

    def _count(self, el: Element, ctx: _Ctx) -> None:
        self.visits += 1
        if self.visits > MAX_VISITS:
            raise ctx.file.error(
                el,
                f"the scene expands to more than {MAX_VISITS} nodes "
                "(DEF/USE or Inline repeated too often)",
            )
        if ctx.depth >= MAX_NESTING:
            raise ctx.file.error(el, f"nodes nest more than {MAX_NESTING} levels deep")

    def _use(self, el: Element, tag: str, use: str, f: _File) -> Element:
        target = f.defs.get(use)
        if target is None:
            close = difflib.get_close_matches(use, list(f.defs), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise f.error(el, f"USE '{use}' names no DEF or id in this file{hint}")
        if _tag(target) != tag:
            raise f.error(el, f"{tag} USE '{use}' names a {_tag(target)} (line {f.line(target)})")
        if target in self.active:
            raise f.error(el, f"USE '{use}' is inside the node it names (line {f.line(target)})")
        return target

    def _group(self, el: Element, tag: str, ctx: _Ctx) -> None:
        if tag == "Transform":
            M, R = _transform_fields(el, ctx.file)
            ctx = ctx._replace(A=ctx.A @ M, R=ctx.R @ R)
        name = _name(el)
        if name is not None and not ctx.instancing:
            ctx = ctx._replace(owner=self._define(name, el, ctx))
        children = _children(el)
        if tag == "Switch":
            children = _chosen(el, children, ctx.file)
        for child in children:
            self.visit(child, ctx)

    def _define(self, name: str, el: Element, ctx: _Ctx) -> _Owner:
        first = self.owners.get(name)
        if first is not None:  # the same name in two files
            where = f"{display_path(first.file)}:{first.line}"
            raise ctx.file.error(el, f"duplicate name '{name}' (first defined at {where})")
        T = _affine(ctx.R, ctx.A[:3, 3])
        if not np.isfinite(T).all():  # each field is finite; their product need not be
            raise ctx.file.error(
                el, f"the pose of '{name}' overflows: its Transform chain has numbers too large"
            )
        if np.abs(T[:3, 3]).max() > MAX_COORDINATE:
            raise ctx.file.error(el, f"'{name}' is{_too_far(T[:3, 3])}")
        owner = _Owner(name, ctx.file.name, ctx.file.line(el), T, inverse(T))
        self.owners[name] = owner
        return owner

    def _inline(self, el: Element, ctx: _Ctx) -> None:
        self.inlines += 1
        if self.inlines > MAX_INLINES:
            raise ctx.file.error(
                el, f"the scene has more than {MAX_INLINES} Inlines (files Inlined again and again)"
            )
        path = self.targets.get(el)
        if path is None:
            path = self.targets[el] = self._inline_path(el, ctx.file)
        if path in ctx.chain:
            loop = " -> ".join(self._rel(p) for p in (*ctx.chain, path))
            raise ctx.file.error(el, f"Inline '{self._rel(path)}' includes itself ({loop})")
        if len(ctx.chain) > MAX_INLINE_DEPTH:
            raise ctx.file.error(
                el, f"Inline '{self._rel(path)}' nests files more than {MAX_INLINE_DEPTH} deep"
            )
        try:
            inlined, scene = self.open(path)
        except CellError as e:  # not X3D at all, perhaps: say which Inline brought it in
            where = f"{display_path(ctx.file.name)}:{ctx.file.line(el)}"
            raise InputError(
                replace(p, message=f"{p.message} (in the file of the Inline at {where})")
                for p in e.problems
            ) from None
        ctx = ctx._replace(file=inlined, chain=(*ctx.chain, inlined.real))
        for child in _children(scene):
            self.visit(child, ctx)

    def _rel(self, path: Path) -> str:
        """A path as the cell names it: relative to the cell folder."""
        return str(path.relative_to(self.root)) if path.is_relative_to(self.root) else str(path)

    def _inline_path(self, el: Element, f: _File) -> Path:
        """The first of the Inline's urls that exists. Urls are relative to the file that
        names them, as in X3D, and every one must stay inside the cell folder."""
        urls = _mfstring(el.get("url", ""))
        if not urls:
            raise f.error(el, "Inline has no url")
        targets = []
        for url in urls:
            if _URL.match(url) and not _DRIVE.match(url):
                raise f.error(
                    el,
                    f"Inline url '{url}' is a URL; only files inside the cell folder "
                    f"{self.root} are allowed",
                )
            target = real(f.real.parent / url)
            if not target.is_relative_to(self.root):
                raise f.error(el, f"Inline url '{url}' points outside the cell folder {self.root}")
            targets.append(target)
        try:  # a name too long for the file system raises rather than "not found"
            found = next((t for t in targets if t.is_file()), targets[0])
            return resolve_inside(self.root, self._rel(found), f.name, *f.position(el))
        except OSError as e:
            raise f.error(
                el, f"Inline url '{_shown(urls[0])}' cannot be read: {e.strerror}"
            ) from None

    def _shape(self, el: Element, ctx: _Ctx) -> None:
        for child in el:
            tag = _tag(child)
            if tag is None or tag == "Appearance" or tag in NO_SURFACE or tag.startswith("Meta"):
                continue
            if tag not in GEOMETRY:
                raise ctx.file.error(
                    child, f"unsupported geometry node '{tag}'; supported: " + ", ".join(GEOMETRY)
                )
            use = child.get("USE")
            geom = self._use(child, tag, use, ctx.file) if use is not None else child
            try:
                V, F = self._geometry(geom, tag, ctx.file)
            except CellError as e:
                owner = ctx.owner or self.loose
                if not self.skip_bad:
                    raise
                owner.problem = owner.problem or e.problems[0]
                continue
            self._add(V, F, ctx, child)

    def _geometry(self, el: Element, tag: str, f: _File) -> tuple[Mat, IntArray]:
        cached = self.cache.get(el)
        if cached is None:
            cached = self.cache[el] = _BUILDERS[tag](el, f, self)
        return cached

    def coordinates(self, el: Element, f: _File) -> Mat:
        """The points of the Coordinate child of a geometry node."""
        coord = next((c for c in el if _tag(c) in COORDINATES), None)
        if coord is None:
            raise f.error(el, f"{_label(el)}: no Coordinate child")
        use = coord.get("USE")
        if use is not None:
            coord = self._use(coord, str(_tag(coord)), use, f)
        pts = self.points.get(coord)
        if pts is None:
            pts = self.points[coord] = _points(coord, "point", f)
        return pts

    def _add(self, V: Mat, F: IntArray, ctx: _Ctx, el: Element) -> None:
        if len(F) == 0:
            return
        self.triangles += len(F)
        self.vertices += len(V)
        if max(self.triangles, self.vertices) > MAX_TRIANGLES:
            raise ctx.file.error(
                el, f"the scene has more than {MAX_TRIANGLES} triangles or vertices"
            )
        owner = ctx.owner or self.loose
        P = transform_points(ctx.A, V)  # in the platform's frame
        V = transform_points(owner.T_inv @ ctx.A, V)  # in the owner's rigid frame
        if not (np.isfinite(V).all() and np.isfinite(P).all()):
            raise ctx.file.error(
                el, f"{_label(el)}: coordinates overflow: the Transform chain has numbers too large"
            )
        far = np.abs(P).max(axis=1).argmax()
        if abs(P[far]).max() > MAX_COORDINATE:
            raise ctx.file.error(el, f"{_label(el)} has a point{_too_far(P[far])}")
        owner.parts.append((V, F))


# --- elements and fields ---------------------------------------------------------------------


def _tag(el: Element) -> str | None:
    """The canonical X3D name of an element; None for comments and processing instructions."""
    tag = el.tag
    if not isinstance(tag, str):
        return None
    if tag[0] == "{":
        tag = tag.split("}", 1)[1]
    return _CANON.get(tag.lower(), tag)


def _name(el: Element) -> str | None:
    name: str | None = el.get("DEF") or el.get("id")
    return name


def _too_far(p: Mat) -> str:
    x, y, z = (f"{round(float(v), 6) + 0.0:.4g}" for v in p)  # to the micrometre, no -0
    return (
        f" at ({x}, {y}, {z}) m, beyond {MAX_COORDINATE:g} m of the platform's origin (an X3D "
        'in millimetres needs a root Transform with scale="0.001 0.001 0.001")'
    )


def _label(el: Element) -> str:
    name = _name(el)
    return f"{_tag(el)} '{name}'" if name else str(_tag(el))


def _children(el: Element) -> list[Element]:
    """The element children that are scene nodes (not a Collision's proxy, not metadata)."""
    return [
        c
        for c in el
        if isinstance(c.tag, str) and c.get("containerField", "children") == "children"
    ]


def _chosen(el: Element, children: list[Element], f: _File) -> list[Element]:
    which = _field(el, "whichChoice", 1, np.array([-1.0]), f, "an integer")[0]
    if which != int(which):
        raise _bad(el, "whichChoice", "an integer", f)
    return [children[int(which)]] if 0 <= which < len(children) else []


def _mfstring(text: str) -> list[str]:
    """X3D MFString: '"a.x3d" "b.x3d"', or a bare single value."""
    if '"' in text:
        return [m.replace('\\"', '"').strip() for m in _QUOTED.findall(text) if m.strip()]
    return [text.strip()] if text.strip() else []


def _plain(text: str) -> str:
    return text.replace(",", " ").strip() if "," in text else text.strip()


def _floats(text: str) -> Mat | None:
    """Whitespace- and/or comma-separated numbers parsed in C; None if any is malformed."""
    text = _plain(text)
    if not text:  # np.fromstring reads whitespace-only text as [-1]
        return np.empty(0)
    try:
        a = np.fromstring(text, sep=" ")
    except ValueError:
        return None
    return a if np.isfinite(a).all() else None


def _ints(text: str) -> IntArray | None:
    text = _plain(text)
    if not text:
        return np.empty(0, np.int64)
    try:
        return np.fromstring(text, dtype=np.int64, sep=" ")
    except ValueError:
        return None


def _first_bad(text: str, integers: bool) -> str:
    """What is wrong with a long number array, token by token (only on the error path)."""
    tokens = _plain(text).split()
    for i, tok in enumerate(tokens):
        try:
            ok = bool(np.isfinite(int(tok) if integers else float(tok)))
        except ValueError:
            ok = False
        if not ok:
            return f"'{_shown(tok)}' (item {i + 1} of {len(tokens)})"
    return f"{len(tokens)} numbers"


def _shown(text: str) -> str:
    return text if len(text) <= 60 else text[:57] + "..."


def _bad(el: Element, attr: str, expect: str, f: _File) -> CellError:
    got = _shown(el.get(attr, ""))
    return f.error(el, f"{_label(el)}: {attr} must be {expect}, got '{got}'")


def _bad_array(el: Element, attr: str, expect: str, f: _File, ints: bool) -> CellError:
    got = _first_bad(el.get(attr, ""), ints)
    return f.error(el, f"{_label(el)}: {attr} must be {expect}, got {got}")


def _field(el: Element, attr: str, n: int, default: Mat, f: _File, expect: str = "") -> Mat:
    """A fixed-size numeric field (SFVec3f, SFRotation, SFFloat), or its default if absent."""
    text = el.get(attr)
    if text is None:
        return default
    a = _floats(text)
    if a is None or a.size != n:
        raise _bad(el, attr, expect or (f"{n} numbers" if n > 1 else "a number"), f)
    return a


def _positive(el: Element, attr: str, n: int, default: float, f: _File) -> Mat:
    expect = f"{n} positive numbers" if n > 1 else "a positive number"
    a = _field(el, attr, n, np.full(n, default), f, expect)
    if (a <= 0).any():
        raise _bad(el, attr, expect, f)
    return a


def _points(el: Element, attr: str, f: _File) -> Mat:
    a = _floats(el.get(attr, ""))
    if a is None or a.size % 3:
        raise _bad_array(el, attr, "x y z triples of numbers", f, False)
    return a.reshape(-1, 3)


def _indices(el: Element, attr: str, f: _File) -> IntArray:
    a = _ints(el.get(attr, ""))
    if a is None:
        raise _bad_array(el, attr, "integers", f, True)
    return a


def _transform_fields(el: Element, f: _File) -> tuple[Mat, Mat]:
    """ISO 19775 Transform: the affine matrix T·C·R·SR·S·SR⁻¹·C⁻¹ and the rotation R alone."""
    t = _field(el, "translation", 3, _ZERO3, f)
    r = _field(el, "rotation", 4, _NO_ROTATION, f)
    s = _field(el, "scale", 3, _ONE3, f)
    if not scale_ok(s):
        raise _bad(el, "scale", f"between {SCALES[0]:g} and {SCALES[1]:g} in size", f)
    c = _field(el, "center", 3, _ZERO3, f)
    so = _field(el, "scaleOrientation", 4, _NO_ROTATION, f)
    R = _rotation(r)
    L = R if (s == 1.0).all() else R @ _scaling(s, _rotation(so))
    return _affine(L, t + c - L @ c if c is not _ZERO3 else t), R


def _rotation(r: Mat) -> Mat:
    return _EYE3 if r[3] == 0.0 else axis_angle_to_matrix(r[:3].tolist(), float(r[3]))


def _scaling(s: Mat, SR: Mat) -> Mat:
    """SR·S·SR⁻¹: a scale along the axes of the scaleOrientation."""
    return (SR * s) @ SR.T


# --- geometry, in the geometry node's own frame ----------------------------------------------

Geometry: TypeAlias = tuple[Mat, IntArray]


def _in_range(el: Element, attr: str, idx: IntArray, n: int, f: _File) -> None:
    bad = idx[(idx < 0) | (idx >= n)]
    if bad.size:
        raise f.error(
            el,
            f"{_label(el)}: {attr} refers to point {int(bad[0])}, "
            + (f"but there are {n} points (0..{n - 1})" if n else "but there are no points"),
        )


def _oriented(el: Element, F: IntArray) -> IntArray:
    return F[:, ::-1].copy() if el.get("ccw", "true").strip().lower() == "false" else F


def _fan(idx: IntArray) -> IntArray:
    """Triangles of -1-separated polygons, each fanned from its first vertex, vectorised."""
    if idx.size and idx[-1] != -1:  # the trailing -1 is optional
        idx = np.append(idx, -1)
    for k in (4, 5):  # the common cases, all triangles or all quads, without the general fan
        if idx.size % k == 0 and (idx[k - 1 :: k] == -1).all():
            faces = idx.reshape(-1, k)[:, : k - 1]
            if (faces >= 0).all():
                return faces if k == 4 else faces[:, _QUAD].reshape(-1, 3)
    sep = idx == -1
    pos = np.arange(idx.size)
    starts = np.concatenate(([True], sep[:-1]))
    first = np.maximum.accumulate(np.where(starts, pos, 0))  # where each one's polygon starts
    nxt = np.append(sep[1:], True)
    mid = ~sep & (pos > first) & ~nxt  # every vertex but the first and last of a polygon
    j = pos[mid]
    return np.stack([idx[first[j]], idx[j], idx[j + 1]], axis=1)


def _indexed_face_set(el: Element, f: _File, loader: _Loader) -> Geometry:
    V = loader.coordinates(el, f)
    idx = _indices(el, "coordIndex", f)
    _in_range(el, "coordIndex", idx[idx != -1], len(V), f)
    return V, _oriented(el, _fan(idx))


def _indexed_triangle_set(el: Element, f: _File, loader: _Loader) -> Geometry:
    V = loader.coordinates(el, f)
    idx = _indices(el, "index", f)
    if idx.size % 3:
        raise _bad_array(el, "index", "integers in triples", f, True)
    _in_range(el, "index", idx, len(V), f)
    return V, _oriented(el, idx.reshape(-1, 3))


def _triangle_set(el: Element, f: _File, loader: _Loader) -> Geometry:
    V = loader.coordinates(el, f)
    if len(V) % 3:
        raise f.error(
            el,
            f"{_label(el)}: the Coordinate must hold whole triangles (3 points each), "
            f"got {len(V)} points",
        )
    return V, _oriented(el, np.arange(len(V), dtype=np.int64).reshape(-1, 3))


def _primitive(mesh: Mesh, T: Mat | None = None) -> Geometry:
    if T is not None:
        mesh = mesh.transformed(T)
    return mesh.vertices, mesh.faces


def _box(el: Element, f: _File, _: _Loader) -> Geometry:
    return _primitive(primitives.box(_positive(el, "size", 3, 2.0, f)))


def _cylinder(el: Element, f: _File, _: _Loader) -> Geometry:
    r = _positive(el, "radius", 1, 1.0, f)[0]
    h = _positive(el, "height", 1, 2.0, f)[0]
    return _primitive(primitives.cylinder(r, h, _SECTIONS), _Z_TO_Y)


def _cone(el: Element, f: _File, _: _Loader) -> Geometry:
    r = _positive(el, "bottomRadius", 1, 1.0, f)[0]
    h = _positive(el, "height", 1, 2.0, f)[0]
    cone = primitives.cone(r, h, _SECTIONS)  # base at z = 0
    return _primitive(cone, _Z_TO_Y @ _affine(np.eye(3), np.array([0.0, 0.0, -h / 2])))


def _sphere(el: Element, f: _File, _: _Loader) -> Geometry:
    r = _positive(el, "radius", 1, 1.0, f)[0]
    return _primitive(primitives.sphere(r))


_BUILDERS: dict[str, Callable[[Element, _File, _Loader], Geometry]] = {
    "Box": _box,
    "Cone": _cone,
    "Cylinder": _cylinder,
    "IndexedFaceSet": _indexed_face_set,
    "IndexedTriangleSet": _indexed_triangle_set,
    "Sphere": _sphere,
    "TriangleSet": _triangle_set,
}


def _mesh(parts: list[Geometry]) -> Mesh | None:
    if not parts:
        return None
    if len(parts) == 1:
        return Mesh(*parts[0])
    offsets = np.cumsum([0] + [len(V) for V, _ in parts[:-1]])
    V = np.concatenate([V for V, _ in parts])
    F = np.concatenate([F + off for (_, F), off in zip(parts, offsets, strict=True)])
    return Mesh(V, F)
