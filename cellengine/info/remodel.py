"""Platforms in the REMODEL cable-routing format (DESIGN 3.2), read directly:

- ``*_ids.wri``: tab-separated ``DEF  label  model``, one element a line;
- ``Jigs_definition_v2.xml``: ``jig``, ``comb`` and ``box`` models in millimetres. Each
  ``guide`` (``couple`` = its index) has a ``key`` pose (``pos`` x, y, z; ``rot`` R, P, Y in
  radians, applied as RotX(R)·RotY(P)·RotZ(Y), about the moving axes) whose attributes
  (length, gap, height, ...) size the slot; the guide's keypoint, named str(couple), is the
  slot centre ``key · Trans(length/2, gap/2, height/2)``. Each guide may also have a
  ``collision`` box, centred at its own pos/rot;
- the X3D file (read by :mod:`cellengine.info.x3d`) gives each DEF's pose and mesh.

Elements are named by their label, so guide 1 of jig J3 is keypoint "1" of element "J3"
(``board.J3.1`` in a plan). Millimetres become metres here, once.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

from cellengine.arrays import Mat
from cellengine.errors import CellError, InputError
from cellengine.geometry import rot_x, rot_y, rot_z, transform
from cellengine.info.files import read_capped
from cellengine.info.models_xml import element_column, source_lines
from cellengine.info.platform import (
    CollisionBox,
    Element,
    Keypoint,
    Platform,
    Source,
    frozen_array,
)
from cellengine.info.x3d import X3DScene, load_x3d
from cellengine.info.xmlsafe import parse_xml

MM = 1e-3
GUIDE_MODELS = ("jig", "comb", "box")


@dataclass(frozen=True)
class IdsRow:
    cad_name: str  # the DEF in the X3D
    label: str  # the element's name in plans
    model: str
    row: int  # line in the ids file


@dataclass(frozen=True)
class RemodelModel:
    name: str
    kind: str  # jig | comb | box | ATC_station
    dimensions: Mapping[str, float]  # metres
    keypoints: Mapping[str, Keypoint]  # in the element frame, metres
    boxes: tuple[CollisionBox, ...]
    source: Source
    tool: str | None = None  # an ATC_station's: the kind of tool it holds (gun, gripper)


def load_remodel_platform(
    name: str,
    T_cell_platform: Mat,
    cad: Path,
    ids: Path,
    models: Path,
    root: Path,
    up: Literal["y", "z"] = "y",
) -> Platform:
    """Read a REMODEL platform; paths are already resolved inside the cell folder."""
    rows = load_ids(ids)
    jigs = load_jigs(models)
    # A REMODEL element's collision model is its box in the Jigs file, so a damaged CAD mesh
    # (the published sample has some) is dropped for modelled elements, not fatal.
    scene = load_x3d(cad, root, up, bad_geometry="skip")
    return assemble(name, T_cell_platform, scene, rows, jigs, ids, models)


def assemble(
    name: str,
    T_cell_platform: Mat,
    scene: X3DScene,
    rows: Sequence[IdsRow],
    models: Mapping[str, RemodelModel],
    ids: Path,
    models_file: Path,
) -> Platform:
    elements: dict[str, Element] = {}
    for row in rows:
        node = scene.node(row.cad_name, ids, row.row)
        model = models.get(row.model)
        if node.mesh_problem is not None and model is None:
            raise InputError(node.mesh_problem)  # nothing else describes its shape
        notes = [] if model else [f"model '{row.model}' is not defined in {models_file.name}"]
        if node.mesh_problem is not None:
            notes.append(f"its CAD mesh was dropped ({node.mesh_problem})")
        elements[row.label] = Element(
            name=row.label,
            model=row.model,
            T_platform_element=node.T_scene_node,
            dimensions=model.dimensions if model else MappingProxyType({}),
            keypoints=model.keypoints if model else MappingProxyType({}),
            mesh=node.mesh,
            boxes=model.boxes if model else (),
            source=Source(str(ids), row.row),
            # A plan that names a keypoint of an unmodelled element then gets a clear error.
            note="; ".join(notes),
        )
    return Platform(name, frozen_array(T_cell_platform), MappingProxyType(elements))


# --- *_ids.wri ---------------------------------------------------------------------------


def load_ids(path: Path) -> tuple[IdsRow, ...]:
    raw = read_capped(path, "csv")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        at = raw.count(b"\n", 0, e.start) + 1
        raise InputError.at("file is not valid UTF-8", path, at) from None
    rows: list[IdsRow] = []
    first_def: dict[str, int] = {}
    first_label: dict[str, int] = {}
    for n, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        row = _ids_row(line, path, n)
        _unique(row.cad_name, "DEF", first_def, path, n)
        _unique(row.label, "label", first_label, path, n)
        rows.append(row)
    return tuple(rows)


def _ids_row(line: str, path: Path, n: int) -> IdsRow:
    fields = [f.strip() for f in line.strip().split("\t")]
    if len(fields) != 3:
        raise InputError.at(
            f"expected 3 tab-separated fields (DEF, label, model), found {len(fields)}"
            + (": separate the fields with tabs" if len(fields) == 1 else ""),
            path,
            n,
        )
    for what, value in zip(("DEF", "label", "model"), fields, strict=True):
        if not value:
            raise InputError.at(f"empty {what}", path, n)
    cad_name, label, model = fields
    if "." in label or any(ch.isspace() for ch in label):
        raise InputError.at(
            f"label '{label}' may not contain dots or spaces "
            "(plans write platform.element.keypoint)",
            path,
            n,
        )
    return IdsRow(cad_name, label, model, n)


def _unique(value: str, what: str, first: dict[str, int], path: Path, line: int) -> None:
    if value in first:
        raise InputError.at(
            f"duplicate {what} '{value}' (first at line {first[value]})", path, line
        )
    first[value] = line


# --- Jigs_definition_v2.xml ------------------------------------------------------------------


class _Doc:
    """The models file and its lines, to put errors at file:line:col."""

    def __init__(self, path: Path) -> None:
        self.path = path

    @cached_property
    def lines(self) -> list[str]:
        return source_lines(self.path)  # read again only when there is an error to report

    def error(self, message: str, el: Any, attr: str | None = None) -> CellError:
        line: int | None = el.sourceline
        return InputError.at(message, self.path, line, element_column(self.lines, el, attr))


def load_jigs(path: Path) -> Mapping[str, RemodelModel]:
    doc = _Doc(path)
    root = parse_xml(path).getroot()
    if root.tag != "data":
        raise doc.error(f"root element is <{root.tag}>; expected <data>", root)
    readers: dict[str, Callable[[_Doc, Any], RemodelModel]] = {
        **dict.fromkeys(GUIDE_MODELS, _guide_model),
        "ATC_station": _atc_model,
    }
    models: dict[str, RemodelModel] = {}
    first: dict[str, int] = {}
    for el in _children(root):
        reader = readers.get(el.tag)
        if reader is None:
            raise doc.error(
                f"unexpected <{el.tag}> in <data>; expected jig, comb, box or ATC_station", el
            )
        model = reader(doc, el)
        if model.name in first:
            raise doc.error(
                f"duplicate model '{model.name}' (first defined at line {first[model.name]})",
                el,
                "model",
            )
        first[model.name] = el.sourceline
        models[model.name] = model
    return MappingProxyType(models)


def _guide_model(doc: _Doc, el: Any) -> RemodelModel:
    """A jig, comb or box: attributes are its dimensions, each guide a keypoint and a box."""
    name = _model_name(doc, el)
    dims = _numeric_attributes(doc, el, skip=("model",))
    keypoints: dict[str, Keypoint] = {}
    boxes: list[CollisionBox] = list(_body_box(dims))
    first: dict[str, int] = {}
    for child in _children(el):
        if child.tag != "guide":
            raise doc.error(f"unexpected <{child.tag}> in <{el.tag}>; expected guide", child)
        kp, box = _guide(doc, child)
        if kp.name in first:
            raise doc.error(
                f"duplicate guide couple '{kp.name}' in model '{name}' "
                f"(first at line {first[kp.name]})",
                child,
                "couple",
            )
        first[kp.name] = child.sourceline
        keypoints[kp.name] = kp
        if box is not None:
            boxes.append(box)
    return RemodelModel(
        name,
        el.tag,
        MappingProxyType(dims),
        MappingProxyType(keypoints),
        tuple(boxes),
        Source(str(doc.path), el.sourceline),
    )


def _body_box(dims: Mapping[str, float]) -> tuple[CollisionBox, ...]:
    """The body's collision extent: x in [xcol1, xcol2], y in [ycol1, ycol2], z in [0, zdim]."""
    if not {"xcol1", "xcol2", "ycol1", "ycol2", "zdim"} <= dims.keys():
        return ()
    lo = (dims["xcol1"], dims["ycol1"], 0.0)
    hi = (dims["xcol2"], dims["ycol2"], dims["zdim"])
    size = (hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2])
    if min(size) <= 0:
        return ()
    centre = [(a + b) / 2 for a, b in zip(lo, hi, strict=True)]
    return (CollisionBox(size, frozen_array(transform(t=centre))),)


def _guide(doc: _Doc, el: Any) -> tuple[Keypoint, CollisionBox | None]:
    _only_attributes(doc, el, ("couple",))
    couple = el.get("couple")
    if couple is None or not re.fullmatch(r"\s*\d{1,9}\s*", couple) or int(couple) < 1:
        raise doc.error(
            f"<guide> attribute 'couple' is {_shown(couple)}; expected its index 1, 2, ...",
            el,
            "couple",
        )
    parts = _parts(doc, el, required=("key",), optional=("collision",))
    key = parts["key"]
    dims = _numeric_attributes(doc, key, required=("length", "gap", "height"))
    # The keypoint is the slot centre: half the slot's length, gap and height from the key.
    slot = transform(t=[dims["length"] / 2, dims["gap"] / 2, dims["height"] / 2])
    kp = Keypoint(str(int(couple)), frozen_array(_pose(doc, key) @ slot), MappingProxyType(dims))
    box = _collision(doc, parts["collision"]) if "collision" in parts else None
    return kp, box


def _collision(doc: _Doc, el: Any) -> CollisionBox | None:
    _only_attributes(doc, el, ("xdim", "ydim", "zdim"))
    size = _numeric_attributes(doc, el, required=("xdim", "ydim", "zdim"))
    for attr, value in size.items():
        if value < 0:
            raise doc.error(f"<collision> attribute '{attr}' is negative", el, attr)
    if not any(size.values()):
        return None  # REMODEL writes a zero box for a guide without one (combs)
    dims = (size["xdim"], size["ydim"], size["zdim"])
    return CollisionBox(dims, frozen_array(_pose(doc, el)))


def _atc_model(doc: _Doc, el: Any) -> RemodelModel:
    """An automatic tool changer station: its tool's base, end and gripper nail as
    keypoints, sizes as dimensions. ``tool`` (gun, gripper) names the tool it holds, which
    the cell's tools describe; it is no dimension."""
    name = _model_name(doc, el)
    dims = _numeric_attributes(doc, el, skip=("model", "tool"))
    keypoints: dict[str, Keypoint] = {}
    for child in _children(el):
        if child.tag in ("tool_base", "tool_end", "gripper_nail"):
            if child.tag in keypoints:
                raise doc.error(f"more than one <{child.tag}> in <{el.tag}>", child)
            _only_attributes(doc, child, ())
            keypoints[child.tag] = Keypoint(child.tag, frozen_array(_pose(doc, child)))
        elif child.tag in ("tool_dim", "finger_dim"):
            prefix = "tool_" if child.tag == "tool_dim" else ""  # finger_dim's are prefixed
            for attr, value in _numeric_attributes(doc, child).items():
                _add_dimension(doc, dims, prefix + attr, value, child, attr)
        else:
            raise doc.error(
                f"unexpected <{child.tag}> in <{el.tag}>; expected tool_base, tool_end, "
                "gripper_nail, tool_dim or finger_dim",
                child,
            )
    return RemodelModel(
        name,
        el.tag,
        MappingProxyType(dims),
        MappingProxyType(keypoints),
        (),
        Source(str(doc.path), el.sourceline),
        el.get("tool"),
    )


def _add_dimension(
    doc: _Doc, dims: dict[str, float], name: str, value: float, el: Any, attr: str
) -> None:
    if name in dims:
        raise doc.error(f"dimension '{name}' is given twice", el, attr)
    dims[name] = value


# --- poses and numbers -----------------------------------------------------------------------

_POSE_PARTS = {"pos": ("x", "y", "z"), "rot": ("R", "P", "Y")}
_NUMBER = re.compile(r"\s*[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?\s*")


def _pose(doc: _Doc, el: Any) -> Mat:
    """``pos`` x, y, z (mm) and ``rot`` R, P, Y (rad): Trans(pos)·RotX(R)·RotY(P)·RotZ(Y)."""
    values: dict[tuple[str, str], float] = {}
    for child in _children(el):
        names = _POSE_PARTS.get(child.tag)
        if names is None:
            raise doc.error(
                f"unexpected <{child.tag}> in <{el.tag}>; expected pos (x, y, z) and rot (R, P, Y)",
                child,
            )
        _only_attributes(doc, child, ("name",))
        axis = child.get("name")
        if axis not in names:
            raise doc.error(
                f"<{child.tag}> name is {_shown(axis)}; expected one of {', '.join(names)}",
                child,
                "name",
            )
        if (child.tag, axis) in values:
            raise doc.error(f'<{child.tag} name="{axis}"> is given twice in <{el.tag}>', child)
        values[child.tag, axis] = _text_number(doc, child, axis)
    for tag, names in _POSE_PARTS.items():
        for axis in names:
            if (tag, axis) not in values:
                raise doc.error(f'<{el.tag}> has no <{tag} name="{axis}">', el)
    xyz = [values["pos", a] * MM for a in "xyz"]
    R, P, Y = (values["rot", a] for a in "RPY")
    return transform(rot_x(R) @ rot_y(P) @ rot_z(Y), xyz)


def _text_number(doc: _Doc, el: Any, axis: str) -> float:
    if any(isinstance(c.tag, str) for c in el):
        raise doc.error(f'<{el.tag} name="{axis}"> holds elements; expected a number', el)
    # Comments may sit inside the element; the number is the text around them.
    text = (el.text or "") + "".join(c.tail or "" for c in el)
    unit = "mm" if el.tag == "pos" else "radians"
    if not _is_number(text):
        raise doc.error(
            f'<{el.tag} name="{axis}"> is {_shown(text.strip())}; expected a number in {unit}',
            el,
        )
    return float(text)


def _numeric_attributes(
    doc: _Doc, el: Any, skip: Sequence[str] = (), required: Sequence[str] = ()
) -> dict[str, float]:
    """Every attribute but ``skip`` as a length in metres, in document order."""
    for attr in required:
        if el.get(attr) is None:
            raise doc.error(f"<{el.tag}> has no '{attr}' attribute (a length in mm)", el)
    out: dict[str, float] = {}
    for attr, value in el.attrib.items():
        if attr in skip:
            continue
        if not _is_number(value):
            raise doc.error(
                f"<{el.tag}> attribute '{attr}' is {_shown(value)}; expected a number in mm",
                el,
                attr,
            )
        out[attr] = float(value) * MM
    return out


def _is_number(text: str) -> bool:
    """A finite decimal number: no nan, inf, hex or digit separators, no overflow."""
    return _NUMBER.fullmatch(text) is not None and math.isfinite(float(text))


def _model_name(doc: _Doc, el: Any) -> str:
    name = (el.get("model") or "").strip()
    if not name:
        raise doc.error(f"<{el.tag}> has no 'model' attribute", el)
    return name


def _only_attributes(doc: _Doc, el: Any, allowed: Sequence[str]) -> None:
    for attr in el.attrib:
        if attr not in allowed:
            expected = f"expected {', '.join(allowed)}" if allowed else "it takes none"
            raise doc.error(f"unexpected attribute '{attr}' on <{el.tag}>; {expected}", el, attr)


def _parts(doc: _Doc, el: Any, required: Sequence[str], optional: Sequence[str]) -> dict[str, Any]:
    """The child elements of ``el`` by tag, each at most once."""
    parts: dict[str, Any] = {}
    allowed = (*required, *optional)
    for child in _children(el):
        if child.tag not in allowed:
            raise doc.error(
                f"unexpected <{child.tag}> in <{el.tag}>; expected {' and '.join(allowed)}",
                child,
            )
        if child.tag in parts:
            raise doc.error(f"more than one <{child.tag}> in <{el.tag}>", child)
        parts[child.tag] = child
    for tag in required:
        if tag not in parts:
            raise doc.error(f"<{el.tag}> has no <{tag}>", el)
    return parts


def _children(el: Any) -> list[Any]:
    """Child elements, skipping comments and processing instructions."""
    return [c for c in el if isinstance(c.tag, str)]


def _shown(value: str | None) -> str:
    if value is None:
        return "missing"
    return f"'{value}'" if len(value) <= 40 else f"'{value[:40]}...'"
