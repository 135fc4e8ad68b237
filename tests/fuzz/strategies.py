"""Hypothesis strategies for hostile inputs: numbers as text (the edges of floats, spellings
of inf and NaN, digit strings, garbage), point clouds that qhull finds hard, X3D Transform
fields and geometry, STL meshes, and edits to a genuine run's journal."""

from __future__ import annotations

import json
import struct
from typing import Any

from hypothesis import strategies as st

# numbers a cell has no business with, spelled as a file would spell them
EDGES = (
    "0",
    "-0",
    "-0.0",
    "5e-324",
    "2.2250738585072014e-308",
    "1e-300",
    "1e-13",
    "1e-9",
    "1e-6",
    "1e-5",
    "1",
    "-1",
    "1e4",
    "1e6",
    "1e7",
    "1e11",
    "1e80",
    "-1e80",
    "1e200",
    "1e308",
    "1.7976931348623157e308",
    "1.8e308",
    "3.4028235e38",
)
SPELLED = (
    "inf",
    "-inf",
    "+inf",
    "INF",
    "Infinity",
    "nan",
    "NaN",
    "-nan",
    "1" + "0" * 400,
    "0." + "0" * 400 + "1",
    "9" * 5000,
    "1e99999",
    "1e-99999",
)
GARBAGE = (
    "",
    "ninety",
    "1e",
    "e5",
    "--1",
    "+-1",
    "0x10",
    "1_000",
    "1..2",
    "١٢",
    "½",
    ".",
    "-",
    "true",
    "null",
    ",",
    "1,,2",
)

# text an attribute may hold: no control characters, surrogates or non-characters (XML 1.0)
_xml_chars = st.characters(codec="utf-8", exclude_categories=("Cc", "Cs", "Cn"))
xml_text = st.text(_xml_chars, max_size=12)

numbers = st.one_of(
    st.sampled_from(EDGES),
    st.sampled_from(SPELLED),
    st.sampled_from(GARBAGE),
    st.floats().map(repr),
    st.floats(-1e4, 1e4).map(repr),
    st.integers(-(10**30), 10**30).map(str),
)
plausible = st.floats(-1e3, 1e3, allow_subnormal=True).map(repr)


def vector(n: int) -> st.SearchStrategy[str]:
    """An SFVec of ``n`` numbers: hostile ones, a plausible one, a wrong count, or any text."""
    return st.one_of(
        st.lists(numbers, min_size=n, max_size=n).map(" ".join),
        st.lists(plausible, min_size=n, max_size=n).map(" ".join),
        st.lists(st.one_of(numbers, plausible), max_size=2 * n + 1).map(" ".join),
        st.lists(numbers, min_size=n, max_size=n).map(", ".join),
        xml_text,
    )


def _numbers(values: st.SearchStrategy[float], n: int) -> st.SearchStrategy[str]:
    return st.lists(values.map(repr), min_size=n, max_size=n).map(" ".join)


# fields a loader accepts, at its bounds: they reach the geometry and qhull
_sound_scale = st.sampled_from([1e-6, -1e-6, 1e-3, -1.0, 1.0, 2.0, 10.0]) | st.floats(1e-6, 100)
_sound_rotation = st.tuples(_numbers(st.floats(-1, 1), 3), st.floats(-1e3, 1e3).map(repr)).map(
    " ".join
)
rotation = st.one_of(
    vector(4),
    _sound_rotation,
    st.sampled_from(["0 0 0 1", "0 0 0 0", "1e-300 0 0 1", "1e300 1e300 0 1", "0 0 1 1e300"]),
)
SOUND_FIELDS = {
    "translation": _numbers(st.floats(-1e5, 1e5), 3),
    "rotation": _sound_rotation,
    "scale": _numbers(_sound_scale, 3),
    "scaleOrientation": _sound_rotation,
    "center": _numbers(st.floats(-1e5, 1e5), 3),
}
HOSTILE_FIELDS = {
    "translation": vector(3),
    "rotation": rotation,
    "scale": vector(3),
    "scaleOrientation": rotation,
    "center": vector(3),
}
scales = st.booleans().flatmap(lambda sound: (SOUND_FIELDS if sound else HOSTILE_FIELDS)["scale"])


@st.composite
def transform_fields(draw: st.DrawFn) -> dict[str, str]:
    """A Transform's fields, sound but for one hostile field at most: a load that refuses the
    first bad field it meets must meet the others sound to get past them."""
    fields = draw(st.fixed_dictionaries({}, optional=SOUND_FIELDS))
    if draw(st.booleans()):
        name = draw(st.sampled_from(list(HOSTILE_FIELDS)))
        fields[name] = draw(HOSTILE_FIELDS[name])
    return fields


# ---------------------------------------------------------------------------- point clouds

OFFSETS = (0.0, 1e-5, 1.0, 99.0, 999.0, 1e4, 99_999.99, 1e5, 1e11, -1e11, 1e80, 1e200)
SPREADS = (0.0, 1e-13, 1e-11, 1e-9, 1e-7, 1e-5, 1e-3, 1.0, 100.0)
_unit = st.floats(-1.0, 1.0)


@st.composite
def clouds(draw: st.DrawFn) -> list[tuple[float, float, float]]:
    """4 to 12 points: a tiny or large spread about a near or far centre, maybe flat."""
    n = draw(st.integers(4, 12))
    offset = draw(st.sampled_from(OFFSETS) | st.floats(-1e4, 1e4))
    spread = draw(st.sampled_from(SPREADS))
    flat = draw(st.sampled_from(["no"] * 5 + ["plane", "line", "point"]))
    points = []
    for _ in range(n):
        u = [draw(_unit) for _ in range(3)]
        if flat in ("plane", "line", "point"):
            u[2] = 0.0
        if flat in ("line", "point"):
            u[1] = u[0]
        if flat == "point":
            u = [0.0, 0.0, 0.0]
        x, y, z = (offset + spread * c for c in u)
        points.append((x, y, z))
    return points


@st.composite
def point_tokens(draw: st.DrawFn) -> list[str]:
    """A cloud as text, x y z per point, now and then one number spoiled."""
    tokens = [repr(float(v)) for p in draw(clouds()) for v in p]
    if draw(st.booleans()) and draw(st.integers(0, 3)) == 0:
        tokens[draw(st.integers(0, len(tokens) - 1))] = draw(numbers)
    return tokens


def fan(n: int) -> list[tuple[int, int, int]]:
    """Triangles over every point of a cloud, fanned from the first (a hull's points)."""
    return [(0, i, i + 1) for i in range(1, n - 1)]


# ---------------------------------------------------------------------------- X3D geometry


@st.composite
def x3d_geometry(draw: st.DrawFn) -> str:
    """A geometry node for a Shape: a Box, a Sphere, a Cylinder or an IndexedFaceSet."""
    kind = draw(st.sampled_from(["Box", "Sphere", "Cylinder", "IndexedFaceSet"]))
    if kind == "Box":
        size = _numbers(st.floats(1e-9, 1e4), 3) if draw(st.booleans()) else vector(3)
        return f"<Box size={_attr(draw(size))}/>"
    if kind == "Sphere":
        return f"<Sphere radius={_attr(draw(numbers))}/>"
    if kind == "Cylinder":
        return f"<Cylinder radius={_attr(draw(numbers))} height={_attr(draw(numbers))}/>"
    tokens = draw(point_tokens())
    n = len(tokens) // 3
    index = " ".join(f"{a} {b} {c} -1" for a, b, c in fan(n))
    index = draw(st.just(index) | st.lists(st.integers(-2, n + 1), max_size=12).map(_spaced))
    return (
        f"<IndexedFaceSet coordIndex={_attr(index)}>"
        f"<Coordinate point={_attr(' '.join(tokens))}/></IndexedFaceSet>"
    )


def _spaced(values: list[int]) -> str:
    return " ".join(map(str, values))


def _attr(value: str) -> str:
    """An XML attribute value, quoted and escaped."""
    text = value.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")
    return '"' + text.replace("\n", "&#10;").replace("\t", "&#9;").replace("\r", "&#13;") + '"'


def transform_attributes(fields: dict[str, str]) -> str:
    return "".join(f" {k}={_attr(v)}" for k, v in fields.items())


# ---------------------------------------------------------------------------------- meshes


@st.composite
def ascii_stl(draw: st.DrawFn) -> bytes:
    """An ASCII STL over a hard cloud: its points fanned into facets."""
    tokens = draw(point_tokens())
    n = len(tokens) // 3
    faces = fan(n) or [(0, 0, 0)]
    lines = ["solid fuzz"]
    for face in faces:
        lines += ["facet normal 0 0 0", "outer loop"]
        lines += [f"vertex {' '.join(tokens[3 * i : 3 * i + 3])}" for i in face]
        lines += ["endloop", "endfacet"]
    lines.append("endsolid fuzz")
    return ("\n".join(lines) + "\n").encode()


_float32 = st.floats(width=32) | st.sampled_from([3.4e38, -3.4e38, 1e-45, 0.0, 1e30])


@st.composite
def binary_stl(draw: st.DrawFn) -> bytes:
    """A binary STL of float32 vertices (inf and NaN among them), its count maybe a lie."""
    triangles = draw(st.lists(st.lists(_float32, min_size=9, max_size=9), max_size=6))
    count = len(triangles) + draw(st.sampled_from([0, 0, 0, 1, -1, 1000, 2**31]))
    body = b"".join(struct.pack("<12fH", 0.0, 0.0, 0.0, *t, 0) for t in triangles)
    return b"fuzz".ljust(80, b" ") + struct.pack("<I", count % 2**32) + body


stl_files = st.one_of(ascii_stl(), ascii_stl(), binary_stl())  # text reaches qhull more

# --------------------------------------------------------------------------------- journal

# JSON values of every type, some a journal reader must not trust
_hostile_json = st.sampled_from(
    [float("nan"), float("inf"), -float("inf"), 1e308, -1.0, 0, 10**400, "", "left", None, True]
)
json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8) | _hostile_json,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner),
    max_leaves=8,
)
ARMS = ("left", "right", "middle", "")
_mode = st.sampled_from(["open", "grasp", "slide", "fly", None, 3])
_gripper = st.fixed_dictionaries(
    {"arm": st.sampled_from(ARMS)},
    optional={"mode": _mode, "holds": st.sampled_from(["cable1", "ghost", None])},
)
_q = st.lists(st.floats(-3.2, 3.2) | _hostile_json, min_size=0, max_size=13)
# entries as a run writes them, their values hostile
forged_entries = st.one_of(
    st.fixed_dictionaries(
        {"entry": st.just("fault")},
        optional={
            "fault": st.fixed_dictionaries(
                {},
                optional={
                    "q": _q,
                    "grippers": st.lists(_gripper, max_size=3),
                    "kind": st.text(max_size=5),
                },
            )
        },
    ),
    st.fixed_dictionaries(
        {"entry": st.just("measured")},
        optional={
            "object": st.sampled_from(["cable1", "ghost", 7]),
            "mass_kg": st.floats() | _hostile_json,
        },
    ),
    st.fixed_dictionaries(
        {
            "entry": st.sampled_from(
                ["start", "resume", "recovery", "end", "timing", "replanned", "sent"]
            )
        },
        optional={"run": json_values, "from_segment": json_values, "segment": json_values},
    ),
    st.dictionaries(st.text(max_size=6), json_values, max_size=3),
)
# lines no run writes: broken bytes, deep nesting, not an object, a torn entry
RAW_LINES = (
    b"\xff\xfe\x00garbage",
    b'{"entry": "finished", "label": "\xc3\x28"}',
    b"[" * 100_000,
    b'{"a":' * 50_000 + b"1" + b"}" * 50_000,
    b"[]",
    b"1",
    b"null",
    b'"entry"',
    b'{"entry": "finished", "segment": 1',
    b'{"entry": "finished", "segment": ' + b"9" * 5000 + b"}",
    b'{"entry": "nope"}',
    b'{"entry": 7}',
    b"{}",
    b"\x00" * 10,
)


@st.composite
def journal_edits(draw: st.DrawFn) -> list[tuple[str, int, Any]]:
    """Edits to a journal's lines: (what, where as an index to wrap, with what)."""
    edit = st.one_of(
        st.tuples(
            st.just("set"),
            st.integers(0, 10**6),
            st.tuples(
                st.sampled_from(["segment", "label", "q", "grippers", "run", "entry", "step"]),
                json_values,
            ),
        ),
        st.tuples(st.just("set_q"), st.integers(0, 10**6), _q),
        st.tuples(
            st.just("set_grippers"),
            st.integers(0, 10**6),
            st.dictionaries(st.sampled_from(ARMS), st.lists(_mode, max_size=3), max_size=3),
        ),
        st.tuples(
            st.just("drop_key"),
            st.integers(0, 10**6),
            st.sampled_from(["segment", "label", "q", "grippers", "run", "entry"]),
        ),
        st.tuples(st.just("insert"), st.integers(0, 10**6), forged_entries),
        st.tuples(st.just("raw"), st.integers(0, 10**6), st.sampled_from(RAW_LINES)),
        st.tuples(st.just("duplicate"), st.integers(0, 10**6), st.none()),
        st.tuples(st.just("delete"), st.integers(0, 10**6), st.none()),
    )
    return draw(st.lists(edit, min_size=1, max_size=4))


def apply_edits(lines: list[bytes], edits: list[tuple[str, int, Any]]) -> list[bytes]:
    """``lines`` (each a JSON object) with ``edits`` applied, in order."""
    out = list(lines)
    for what, where, value in edits:
        n = len(out) + (what in ("insert", "raw"))  # an insertion may go after the last line
        if n == 0:
            continue
        i = where % n
        if what == "insert":
            out.insert(i, _dumps(value))
        elif what == "raw":
            out.insert(i, value)
        elif what == "duplicate":
            out.insert(i, out[i])
        elif what == "delete":
            del out[i]
        else:
            out[i] = _edited(out[i], what, value)
    return out


def _edited(line: bytes, what: str, value: Any) -> bytes:
    try:
        entry = json.loads(line)
    except ValueError:  # an earlier raw line: left as it is
        return line
    if not isinstance(entry, dict):
        return line
    if what == "drop_key":
        entry.pop(value, None)
    elif what == "set":
        entry[value[0]] = value[1]
    else:
        entry[what.removeprefix("set_")] = value
    return _dumps(entry)


def _dumps(value: Any) -> bytes:
    return json.dumps(value).encode()  # NaN and Infinity as Python writes them
