"""Property: mutate the files of a good cell (delete, duplicate or swap lines, change a value,
delete or rename a key, truncate, insert bytes) and validate. The result is success, or
problems that each name a file, say what is wrong and, in a YAML, XML or CSV file, give a
line inside it. Never another exception; printing the problems never fails either.

The examples are derandomized, so CI sees the same ones every run.
"""

from __future__ import annotations

import contextlib
import io
import re
import shutil
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cellengine.commands import validate as validate_command
from cellengine.commands.validate import validate_paths

ROOT = Path(__file__).resolve().parent.parent
CABLE_ROUTING = ROOT / "cells" / "cable_routing"
REMODEL_SAMPLE = Path(__file__).resolve().parent / "data" / "platforms" / "remodel"

YAML = ["cell.yaml", "objects.yaml", "plan_straight.yaml", "plan_one_turn.yaml"]
YAML += ["plan_two_turns.yaml"]
SMALL = ["holder/models.xml", "holder/map.csv", "routing/models.xml", "routing/map.csv"]
X3D = ["holder/holder.x3d", "routing/routing.x3d"]
REMODEL = ["board/platform_ids.wri", "board/Jigs_definition_v2.xml", "board/platform_cad.x3d"]

# Files whose problems must carry a line (every format but size caps, never reached here).
LINED = {".yaml", ".yml", ".xml", ".x3d", ".csv", ".wri"}

# Values that have broken parsers: wrong kinds, extremes, markup, escapes, references.
SPECIAL = [
    b"",
    b" ",
    b"0",
    b"-0",
    b"-1",
    b"1e308",
    b"-1e308",
    b"1e999",
    b"9" * 40,
    b"0x1F",
    b"1_000",
    b".nan",
    b".inf",
    b"nan",
    b"null",
    b"~",
    b"true",
    b"no",
    b"[]",
    b"{}",
    b"[1, 2]",
    b"{a: 1}",
    b"- ",
    b": ",
    b"---",
    b"#",
    b"*a",
    b"&a",
    b"<<: *a",
    b"!!python/object/apply:os.system [ls]",
    b"!include x",
    b'"\\ud800"',
    b'"\\0"',
    b'"\\x07"',
    b"\t",
    b"\x00",
    b"\x07",
    b"\xff\xfe",
    b"\xe2\x80\xae",
    "ä‽😀".encode(),
    b"a.b",
    b"a b",
    b"../x",
    b"/etc/passwd",
    b"http://example.com/x",
    b"file:///etc/passwd",
    b"<",
    b">",
    b"&",
    b"&amp;",
    b"&xxe;",
    b"&#0;",
    b'"',
    b"'",
    b",",
    b";",
    b"-1 -1 -1",
    b"0 0 0 0",
    b"<!ENTITY x 'y'>",
    b"]]>",
]

EDITS = [
    "delete line",
    "duplicate line",
    "swap lines",
    "change value",
    "key",
    "truncate",
    "insert bytes",
]
_TOKEN = re.compile(rb"-?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?|[A-Za-z_][\w.\-/]*")
_KEY = {  # the names a mutation may delete or rename, per kind of file
    "yaml": re.compile(rb"([A-Za-z_][\w-]*)(\s*:(?:\s|$))", re.M),
    "xml": re.compile(rb"\s([A-Za-z_:][\w:.-]*)(\s*=\s*(?:\"[^\"]*\"|'[^']*'))"),
    "csv": re.compile(rb"([^,\n\t]+)([,\t]?)"),
}


def _kind(name: str) -> str:
    suffix = Path(name).suffix
    return {".yaml": "yaml", ".xml": "xml", ".x3d": "xml"}.get(suffix, "csv")


def _lines(data: bytes) -> list[bytes]:
    return data.splitlines(keepends=True) or [b""]


@st.composite
def _value(draw: st.DrawFn) -> bytes:
    choice = draw(st.integers(0, 3))
    if choice == 0:
        return draw(st.sampled_from(SPECIAL))
    if choice == 1:
        return str(draw(st.integers(-(10**20), 10**20))).encode()
    if choice == 2:
        x = draw(st.floats(allow_nan=True, allow_infinity=True))
        return repr(x).encode()
    return draw(st.text(max_size=8)).encode("utf-8", "surrogatepass")


@st.composite
def _mutate(draw: st.DrawFn, data: bytes, name: str) -> tuple[bytes, str]:
    """One mutation of ``data`` and what it was, for the failure report."""
    kind = draw(st.sampled_from(EDITS))
    lines = _lines(data)
    if kind == "delete line":
        i = draw(st.integers(0, len(lines) - 1))
        return b"".join(lines[:i] + lines[i + 1 :]), f"{kind} {i + 1}"
    if kind == "duplicate line":
        i = draw(st.integers(0, len(lines) - 1))
        return b"".join(lines[: i + 1] + lines[i:]), f"{kind} {i + 1}"
    if kind == "swap lines":
        i = draw(st.integers(0, len(lines) - 1))
        j = draw(st.integers(0, len(lines) - 1))
        lines[i], lines[j] = lines[j], lines[i]
        return b"".join(lines), f"{kind} {i + 1} {j + 1}"
    if kind == "truncate":
        at = draw(st.integers(0, len(data)))
        return data[:at], f"{kind} at {at}"
    if kind == "insert bytes":
        at = draw(st.integers(0, len(data)))
        junk = draw(st.binary(min_size=1, max_size=8) | st.sampled_from(SPECIAL))
        return data[:at] + junk + data[at:], f"{kind} {junk!r} at {at}"
    if kind == "change value":
        tokens = [m for m in _TOKEN.finditer(data) if not _in_comment(data, m.start(), name)]
        if not tokens:
            return data, "nothing to change"
        m = tokens[draw(st.integers(0, len(tokens) - 1))]
        new = draw(_value() | st.just(_flip(m.group())))
        return data[: m.start()] + new + data[m.end() :], f"{kind} {m.group()!r} -> {new!r}"
    keys = list(_KEY[_kind(name)].finditer(data))
    if not keys:
        return data, "no key"
    m = keys[draw(st.integers(0, len(keys) - 1))]
    if draw(st.booleans()):  # delete the key and, in YAML and XML, its value
        end = m.end() if _kind(name) != "yaml" else _line_end(data, m.end())
        return data[: m.start(1)] + data[end:], f"delete key {m.group(1)!r}"
    new = draw(
        st.sampled_from([m.group(1)[:-1], m.group(1).upper(), m.group(1) + b"x", b"x" + m.group(1)])
        | st.from_regex(rb"\A[a-z_][a-z0-9_]{0,8}\Z")
    )
    return data[: m.start(1)] + new + data[m.end(1) :], f"rename key {m.group(1)!r} -> {new!r}"


def _in_comment(data: bytes, at: int, name: str) -> bool:
    """Whether ``at`` is in a comment, where a changed value would change nothing."""
    if _kind(name) == "xml":
        return data.rfind(b"<!--", 0, at) > data.rfind(b"-->", 0, at)
    if _kind(name) == "yaml":
        line = data[data.rfind(b"\n", 0, at) + 1 : at]
        return line.lstrip().startswith(b"#") or b" #" in line
    return False


def _flip(token: bytes) -> bytes:
    """A number's sign flipped, or a name turned into a number."""
    if re.fullmatch(rb"-?\d.*", token):
        return token[1:] if token.startswith(b"-") else b"-" + token
    return b"1"


def _line_end(data: bytes, at: int) -> int:
    """Where a YAML value that starts at ``at`` ends: a flow item's ',' or '}', else the line."""
    for i in range(at, len(data)):
        if data[i : i + 1] in (b",", b"}", b"\n"):
            return i
    return len(data)


# Values of every YAML kind, for mutations of the loaded document, with names that resolve.
_NAMES = ["routing.guide1", "holder.comb_a.slot", "cable1", "ur5e", "sim", "mm", "deg", "left"]
_LEAVES = (
    st.none()
    | st.booleans()
    | st.integers(-(10**30), 10**30)
    | st.floats()
    | st.text(max_size=10)
    | st.sampled_from(_NAMES)
)
_TREES = st.recursive(
    _LEAVES,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.text(max_size=6) | st.sampled_from(["skill", "xyz", "kind"]), inner, max_size=3
        )
    ),
    max_leaves=6,
)


def _paths(node: Any, at: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield at
    items = (
        node.items()
        if isinstance(node, dict)
        else enumerate(node)
        if isinstance(node, list)
        else ()
    )
    for key, value in items:
        yield from _paths(value, (*at, key))


@st.composite
def _mutate_tree(draw: st.DrawFn, data: bytes) -> tuple[bytes, str]:
    """A mutation of the loaded YAML document (a value of another kind, a key deleted or
    renamed), written back as YAML: wrong kinds and shapes that line edits seldom make."""
    doc = yaml.safe_load(data)  # a good file: the mutation is the first in this file
    path = draw(st.sampled_from(list(_paths(doc))))
    if not path:
        new = draw(_TREES)
        return yaml.safe_dump(new).encode(), f"document -> {new!r}"
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    key = path[-1]
    op = draw(
        st.sampled_from(
            ["replace", "delete", "rename"] if isinstance(key, str) else ["replace", "delete"]
        )
    )
    if op == "replace":
        parent[key] = draw(_TREES)
        what = f"{path} -> {parent[key]!r}"
    elif op == "delete":
        del parent[key]
        what = f"delete {path}"
    else:
        new_key = draw(st.text(max_size=8) | st.sampled_from([key.upper(), key[:-1], key + "s"]))
        parent[new_key] = parent.pop(key)
        what = f"rename {path} -> {new_key!r}"
    return yaml.safe_dump(doc, sort_keys=False, allow_unicode=True).encode(), what


@st.composite
def _mutations(draw: st.DrawFn, files: list[str], folder: Path) -> dict[str, tuple[bytes, str]]:
    """One to three mutations, in one file or several."""
    out: dict[str, tuple[bytes, str]] = {}
    for _ in range(draw(st.integers(1, 3))):
        name = draw(st.sampled_from(files))
        data = out[name][0] if name in out else (folder / name).read_bytes()
        if name not in out and name.endswith(".yaml") and draw(st.booleans()):
            mutated, what = draw(_mutate_tree(data))
        else:
            mutated, what = draw(_mutate(data, name))
        out[name] = (mutated, (out[name][1] + "; " if name in out else "") + what)
    return out


def _check(folder: Path, mutations: dict[str, tuple[bytes, str]]) -> None:
    originals = {name: (folder / name).read_bytes() for name in mutations}
    try:
        for name, (data, _) in mutations.items():
            (folder / name).write_bytes(data)
        results = validate_paths([folder])
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            validate_command._text(results)
        out.getvalue().encode("utf-8")  # what a terminal gets: no unprintable surrogates
        assert results, "no file was checked"
        for r in results:
            for p in r.problems:
                assert p.file, f"{p} names no file"
                assert p.message.strip(), f"{p} says nothing"
                path = Path(p.file)
                if path.suffix in LINED and "byte limit" not in p.message:
                    assert p.line is not None, f"{p} has no line"
                    count = len(_lines(path.read_bytes())) if path.is_file() else 0
                    assert 1 <= p.line <= count + 1, f"{p}: line outside the file"
                    assert p.col is None or p.col >= 1, f"{p}: bad column"
    finally:
        for name, data in originals.items():
            (folder / name).write_bytes(data)


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The reference cable-routing cell, plus a REMODEL platform from the test data."""
    folder = tmp_path_factory.mktemp("mutations") / "cable_routing"
    shutil.copytree(CABLE_ROUTING, folder)
    shutil.copytree(REMODEL_SAMPLE, folder / "board")
    text = (folder / "cell.yaml").read_text()
    board = (
        "  board:    {pose: {xyz: [600, 300, 0]}, format: remodel, up: z,\n"
        "             cad: board/platform_cad.x3d, ids: board/platform_ids.wri,\n"
        "             models: board/Jigs_definition_v2.xml}\n"
        "obstacles:\n"
    )
    (folder / "cell.yaml").write_text(text.replace("obstacles:\n", board, 1))
    assert all(not r.problems for r in validate_paths([folder])), "the base cell must be valid"
    yield folder


COMMON = {"derandomize": True, "deadline": None, "database": None}
SLOW_OK = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]


@settings(max_examples=300, suppress_health_check=SLOW_OK, **COMMON)  # type: ignore[arg-type]
@given(data=st.data())
def test_yaml_mutations(cell: Path, data: st.DataObject) -> None:
    _check(cell, data.draw(_mutations(YAML, cell)))


@settings(max_examples=150, suppress_health_check=SLOW_OK, **COMMON)  # type: ignore[arg-type]
@given(data=st.data())
def test_models_and_map_mutations(cell: Path, data: st.DataObject) -> None:
    _check(cell, data.draw(_mutations(SMALL, cell)))


@settings(max_examples=100, suppress_health_check=SLOW_OK, **COMMON)  # type: ignore[arg-type]
@given(data=st.data())
def test_x3d_mutations(cell: Path, data: st.DataObject) -> None:
    _check(cell, data.draw(_mutations(X3D, cell)))


@settings(max_examples=100, suppress_health_check=SLOW_OK, **COMMON)  # type: ignore[arg-type]
@given(data=st.data())
def test_remodel_mutations(cell: Path, data: st.DataObject) -> None:
    _check(cell, data.draw(_mutations(REMODEL, cell)))
