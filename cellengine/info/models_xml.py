"""The element-model XML of a native platform (DESIGN 3.2), validated against
``schemas/element-models.xsd`` and converted once to metres and radians.

```xml
<elements units="mm" angles="deg">
  <element model="guide_u">
    <dimension name="gap" value="10"/>
    <keypoint name="slot" xyz="0 0 55" rpy="0 0 90"/>
  </element>
</elements>
```
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from importlib.resources import files
from pathlib import Path
from types import MappingProxyType
from typing import Any

from lxml import etree

from cellengine.errors import CellError, InputError, Problem
from cellengine.geometry import pose
from cellengine.info.bounds import MAX_COORDINATE
from cellengine.info.files import read_capped
from cellengine.info.platform import Keypoint, Source, frozen_array
from cellengine.info.xmlsafe import parse_xml

# The repo's schemas/ folder, installed as the package cellengine.schemas.
SCHEMA = Path(str(files("cellengine.schemas") / "element-models.xsd"))

LENGTH = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
ANGLE = {"rad": 1.0, "deg": math.pi / 180.0}


@dataclass(frozen=True)
class ElementModel:
    """One ``<element model=...>``: dimensions in metres, keypoints in the element frame."""

    name: str
    dimensions: Mapping[str, float]
    keypoints: Mapping[str, Keypoint]  # document order: the first is the default
    source: Source


def load_models(path: Path) -> Mapping[str, ElementModel]:
    """Models of ``path`` by name, in document order. Every mistake is an InputError."""
    tree = parse_xml(path)
    schema = _schema()
    if not schema.validate(tree):
        raise InputError(_schema_problems(schema.error_log, path, source_lines(path)))
    root = tree.getroot()
    length = LENGTH[root.get("units", "m").strip()]  # xs:token: the schema allows spaces
    angle = ANGLE[root.get("angles", "rad").strip()]
    models: dict[str, ElementModel] = {}
    first: dict[str, int] = {}
    for el in root.iterchildren("element"):
        name = el.get("model")
        _unique(name, "model", el, first, path)
        models[name] = _model(el, length, angle, path)
    return MappingProxyType(models)


def _model(el: Any, length: float, angle: float, path: Path) -> ElementModel:
    dims: dict[str, float] = {}
    kps: dict[str, Keypoint] = {}
    first_dim: dict[str, int] = {}
    first_kp: dict[str, int] = {}
    for child in el.iterchildren("dimension", "keypoint"):
        name = child.get("name")
        if child.tag == "dimension":
            _unique(name, "dimension", child, first_dim, path)
            dims[name] = _numbers(child, "value", path)[0] * length
            if not 0.0 < dims[name] <= MAX_COORDINATE:  # a size, in a cell of metres
                text = child.get("value")
                raise _error(
                    f"dimension '{name}': {text} is not a size (more than 0, at most "
                    f"{MAX_COORDINATE:g} m)",
                    child,
                    path,
                    "value",
                )
        else:
            _unique(name, "keypoint", child, first_kp, path)
            xyz = [v * length for v in _numbers(child, "xyz", path)]
            if max(map(abs, xyz)) > MAX_COORDINATE:
                text = child.get("xyz")
                raise _error(
                    f"keypoint '{name}': xyz '{text}' is beyond {MAX_COORDINATE:g} m of its "
                    "element",
                    child,
                    path,
                    "xyz",
                )
            rpy = [v * angle for v in _numbers(child, "rpy", path)]
            kps[name] = Keypoint(name, frozen_array(pose(xyz, rpy)))
    return ElementModel(
        el.get("model"),
        MappingProxyType(dims),
        MappingProxyType(kps),
        Source(str(path), el.sourceline),
    )


def _numbers(el: Any, attr: str, path: Path) -> list[float]:
    """A schema-valid numeric attribute; the schema cannot refuse overflow such as 1e999."""
    text = el.get(attr, "0 0 0")  # only rpy is optional
    values = [float(v) for v in text.split()]
    if not all(math.isfinite(v) for v in values):
        raise _error(f"<{el.tag}> attribute '{attr}': '{text}' is out of range", el, path, attr)
    return values


def _unique(name: str, what: str, el: Any, first: dict[str, int], path: Path) -> None:
    """Record ``name``'s line in ``first``; a second definition is an error naming the first."""
    if name in first:
        attr = "model" if what == "model" else "name"
        raise _error(
            f"duplicate {what} '{name}' (first defined at line {first[name]})", el, path, attr
        )
    first[name] = el.sourceline


def _error(message: str, el: Any, path: Path, attr: str) -> CellError:
    # The file is read again for the column only when there is an error to report.
    col = element_column(source_lines(path), el, attr)
    return InputError.at(message, path, el.sourceline, col)


@lru_cache(maxsize=1)
def _schema() -> Any:
    # The XSD goes through the same secure parser as user files: no DTD, entities, network.
    return etree.XMLSchema(parse_xml(SCHEMA, "xml"))


# --- readable schema errors ------------------------------------------------------------------

_NUMBER_PATTERN = r"[+\-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)([eE][+\-]?[0-9]+)?"
_PATTERNS = {
    _NUMBER_PATTERN: "is not a finite number",
    r"[^.\s]+": "is not a name: use no dots or spaces (plans write platform.element.keypoint)",
    r"\S+": "is not a name: it must be non-empty, without spaces",
}


def _pattern(m: re.Match[str]) -> str:
    return f"'{m.group(1)}' " + _PATTERNS.get(m.group(2), f"does not match '{m.group(2)}'")


def _one_of(text: str) -> str:
    return ", ".join(n.strip(" '") for n in text.split(","))


def _choices(m: re.Match[str]) -> str:
    return f"'{m.group(1)}' is not one of {_one_of(m.group(2))}"


def _expected(m: re.Match[str]) -> str:
    return f"unexpected element; expected {_one_of(m.group(2))}"


# libxml2's messages, reworded for people who write the file rather than the schema.
_REWRITES: list[tuple[re.Pattern[str], str | Callable[[re.Match[str]], str]]] = [
    (
        re.compile(r"^Element '([^']+)', attribute '([^']+)': The attribute '[^']+' "),
        r"<\1>: attribute '\2' ",
    ),
    (re.compile(r"^Element '([^']+)', attribute '([^']+)': "), r"<\1> attribute '\2': "),
    (re.compile(r"^Element '([^']+)': The attribute"), r"<\1>: attribute"),
    (re.compile(r"^Element '([^']+)': "), r"<\1>: "),
    (
        re.compile(
            r"\[facet 'pattern'\] The value '([^']*)' is not accepted by the pattern '(.*)'\."
        ),
        _pattern,
    ),
    (
        re.compile(
            r"\[facet 'enumeration'\] The value '([^']*)' is not an element of the set \{(.*)\}"
        ),
        _choices,
    ),
    (
        re.compile(
            r"\[facet 'length'\] The value '([^']*)' has a length of '(\d+)'; "
            r"this differs from the allowed length of '(\d+)'\."
        ),
        r"'\1' has \2 numbers; expected \3 separated by spaces",
    ),
    (
        re.compile(r"'([^']*)' is not a valid value of the atomic type 'number'\."),
        r"'\1' is not a number",
    ),
    (
        re.compile(r"No matching global declaration available for the validation root\."),
        "this is not an element-model file; expected the root element <elements>",
    ),
    (re.compile(r"This element is not expected\. Expected is (one of )?\( (.*) \)"), _expected),
]
_ATTR = re.compile(r"^Element '([^']+)'(?:, attribute '([^']+)')?")


def _readable(message: str) -> str:
    for pattern, repl in _REWRITES:
        message = pattern.sub(repl, message)
    return message.rstrip(".")


def _schema_problems(log: Any, path: Path, lines: Sequence[str]) -> list[Problem]:
    """One problem per element and attribute: libxml2 follows an item error in a list with
    a second error about the whole list, which would only repeat it."""
    problems: list[Problem] = []
    seen: set[tuple[int, str]] = set()
    for entry in log:
        m = _ATTR.match(entry.message)
        key = (entry.line, m.group(0) if m else entry.message)
        if key in seen:
            continue
        seen.add(key)
        tag, attr = (m.group(1), m.group(2)) if m else ("", None)
        col = column(lines, entry.line, tag, attr) if tag else None
        problems.append(Problem(_readable(entry.message), str(path), entry.line, col))
    return problems


# --- columns: libxml2 reports lines only, so find the tag (and attribute) on its line --------


def source_lines(path: Path) -> list[str]:
    return read_capped(path, "xml").decode("utf-8", errors="replace").splitlines()


def column(
    lines: Sequence[str], line: int | None, tag: str, attr: str | None = None, nth: int = 0
) -> int | None:
    """1-based column of ``attr=`` (else of ``<tag``) in the ``nth`` ``<tag`` on ``line``,
    or None if not found there."""
    if line is None or not 1 <= line <= len(lines):
        return None
    text = lines[line - 1]
    start = -1
    if tag:
        for _ in range(nth + 1):
            start = text.find(f"<{tag}", start + 1)
            if start < 0:
                break
    if attr:
        m = re.compile(rf"\b{re.escape(attr)}\s*=").search(text, max(start, 0))
        if m:
            return m.start() + 1
    return start + 1 if start >= 0 else None


def element_column(lines: Sequence[str], el: Any, attr: str | None = None) -> int | None:
    """Column of element ``el`` (or its ``attr``), telling apart same-tag elements that
    share its line."""
    line = el.sourceline
    nth = 0
    for other in el.getroottree().iter(el.tag):
        if other is el:
            break
        nth += other.sourceline == line
    return column(lines, line, el.tag, attr, nth)
