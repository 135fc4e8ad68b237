"""REMODEL's ``WH_configuration.xml`` (HARNESS.md 1.6): the wiring harnesses, each a first
connector with branches (``end_connector``, whose label an RC row may name) of cables at
pins::

    <data>
      <wiring_harness id="1" first_connector="WH1" tray="B3.1">
        <end_connector label="GR11">
          <cable Row1="0" Col1="0">CA1</cable>
          <cable Row1="1" Col1="0">CA2</cable>
        </end_connector>
      </wiring_harness>
    </data>

Every attribute is optional as far as the file goes (the published single-cable sample has no
id); what an operation needs is checked where it is needed. ``Row1`` counts a cable's place
at the first connector from the bottom (REMODEL's planner reads it as an ordinal, the vision
service from 0 at the bottom); ``Col1``, ``Row2`` and ``Col2`` are kept but unused by REMODEL.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cellengine.errors import InputError, Problem
from cellengine.info.xmlsafe import parse_xml

_WHOLE = re.compile(r"^\s*\d{1,9}\s*$")
FREE = "free"  # the end label of a cable with no end connector (the published sample)


@dataclass(frozen=True)
class PinnedCable:
    cable: str
    row1: int | None  # place at the first connector, from the bottom
    col1: int | None
    row2: int | None  # at the branch's end connector
    col2: int | None
    line: int


@dataclass(frozen=True)
class BranchXml:
    label: str | None  # the end_connector's label: a branch, an end connector, or Free
    cables: tuple[PinnedCable, ...]
    line: int

    @property
    def free(self) -> bool:
        return self.label is None or self.label.lower() == FREE


@dataclass(frozen=True)
class HarnessXml:
    id: str | None
    first: str | None  # first_connector: a connector label of the components file
    tray: str | None
    branches: tuple[BranchXml, ...]
    line: int

    @property
    def cables(self) -> tuple[PinnedCable, ...]:
        return tuple(c for b in self.branches for c in b.cables)


def load_wiring(path: Path) -> tuple[tuple[HarnessXml, ...], list[Problem]]:
    """Every harness in document order, and the warnings: what REMODEL's own code would
    read differently or silently drop. Structural mistakes are errors at their line."""
    root = parse_xml(path).getroot()
    problems: list[Problem] = []
    warnings: list[Problem] = []
    if root.tag != "data":
        raise InputError.at(f"root element is <{root.tag}>; expected <data>", path, root.sourceline)
    harnesses = []
    for el in _children(root):
        if el.tag != "wiring_harness":
            msg = f"unexpected <{el.tag}> in <data>; expected wiring_harness"
            problems.append(Problem(msg, str(path), el.sourceline))
            continue
        harnesses.append(_harness(el, path, problems, warnings))
    problems += _duplicates(harnesses, path)
    if problems:
        raise InputError(problems)
    return tuple(harnesses), warnings


def _harness(el: Any, path: Path, problems: list[Problem], warnings: list[Problem]) -> HarnessXml:
    hid = _text(el.get("id"))
    if hid is not None and len(hid) > 1:
        msg = f"harness id '{hid}': REMODEL's planner reads one character of it (WH{hid[0]})"
        warnings.append(Problem(msg, str(path), el.sourceline))
    branches: list[BranchXml] = []
    loose: list[PinnedCable] = []
    for child in _children(el):
        if child.tag == "end_connector":
            cables = [_cable(c, path, problems) for c in _children(child) if c.tag == "cable"]
            for c in _children(child):
                if c.tag != "cable":
                    msg = f"unexpected <{c.tag}> in <end_connector>; expected cable"
                    problems.append(Problem(msg, str(path), c.sourceline))
            if not cables:
                msg = "an <end_connector> with no <cable>: a branch has at least one"
                problems.append(Problem(msg, str(path), child.sourceline))
            label = _text(child.get("label"))
            branches.append(BranchXml(label, tuple(cables), child.sourceline))
        elif child.tag == "cable":  # a cable straight under the harness: a free end
            loose.append(_cable(child, path, problems))
        else:
            msg = f"unexpected <{child.tag}> in <wiring_harness>; expected end_connector or cable"
            problems.append(Problem(msg, str(path), child.sourceline))
    if loose:
        branches.append(BranchXml(None, tuple(loose), loose[0].line))
    first, tray = _text(el.get("first_connector")), _text(el.get("tray"))
    return HarnessXml(hid, first, tray, tuple(branches), el.sourceline)


def _cable(el: Any, path: Path, problems: list[Problem]) -> PinnedCable:
    name = (el.text or "").strip()
    if not name:
        problems.append(Problem("empty <cable> (expected a cable label)", str(path), el.sourceline))
    pins = []
    for attr in ("Row1", "Col1", "Row2", "Col2"):
        value = el.get(attr)
        if value is not None and not _WHOLE.match(value):
            msg = f"<cable> {attr} is '{value[:20]}'; expected a whole number (0, 1, ...)"
            problems.append(Problem(msg, str(path), el.sourceline))
            value = None
        pins.append(None if value is None else int(value))
    row1, col1, row2, col2 = pins
    return PinnedCable(name, row1, col1, row2, col2, el.sourceline)


def _duplicates(harnesses: list[HarnessXml], path: Path) -> list[Problem]:
    """A cable, branch label, first connector or id used twice: REMODEL keys its tables
    by them, so the later one would silently replace the earlier."""
    out: list[Problem] = []
    seen: dict[tuple[str, str], int] = {}

    def once(kind: str, value: str | None, line: int) -> None:
        if value is None:
            return
        if (kind, value) in seen:
            msg = f"{kind} '{value}' is used again (first at line {seen[kind, value]})"
            out.append(Problem(msg, str(path), line))
        else:
            seen[kind, value] = line

    for h in harnesses:
        once("harness id", h.id, h.line)
        once("first_connector", h.first, h.line)
        for b in h.branches:
            once("end_connector label", None if b.free else b.label, b.line)
            for c in b.cables:
                once("cable", c.cable or None, c.line)
        pins: dict[tuple[int, int], str] = {}
        for c in h.cables:
            if c.row1 is None:
                continue
            key = (c.row1, c.col1 or 0)
            if key in pins:
                msg = f"cable {c.cable} has the pins Row1={c.row1} Col1={c.col1} of {pins[key]}"
                out.append(Problem(msg, str(path), c.line))
            pins[key] = c.cable
    return out


def _children(el: Any) -> list[Any]:
    return [c for c in el if isinstance(c.tag, str)]


def _text(value: str | None) -> str | None:
    return (value or "").strip() or None
