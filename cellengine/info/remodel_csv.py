"""The process files of a REMODEL cell (DESIGN 3.2, HARNESS.md 1.5 and 1.7): the
components and the assembly sequence, ``;``-separated CSVs with a header (the wiring-harness
XML is cellengine.info.remodel_harness's).

```
Type;Model;Reference;Label;Color;length;Diameter;x;y;z;Type
Connector;VGA;99999999;CON1;Grey;;;32.9;14.64;46.55;
Cable;;;CA1;Grey;500;5.1;;;;

Order;Type of operation;Label;Spot
1;EC;CON1;C2.1-C1.1
2;PC;CON1;J8.1.L
3;RC;CON1;J3.1-J4.1-J1.1-J2.1
```

The later REMODEL system adds EC's one-comb form (``C1.1.L``), RC rows naming a branch
(``RC;GR11;J1.1-J2.1``) and taping (``T;WH1;J1.1-J2.1-J2.1``).

Rows are CSV line numbers (the header is row 1), so errors point where a spreadsheet or an
editor does. Lengths stay in the file's millimetres: the importer writes them into an
``objects.yaml`` that declares ``mm``, and conversion happens once, when that is loaded.
"""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from cellengine.errors import InputError, Problem, known
from cellengine.info.csvrows import records
from cellengine.info.files import read_capped

SEP = ";"
T = TypeVar("T")
Number = int | float  # ints stay ints so the written YAML reads as the CSV did

# A PC spot's last letter picks the arm that places the connector; the importer writes
# the robot of that name, so a cell used with REMODEL plans names its arms left and right.
ARMS = {"L": "left", "R": "right"}

# Operation -> (how many spots its Spot names, how to write them), in the REMODEL order.
# EC has two grammars: the published sample's two combs (connector end first) and the later
# system's one comb with the arm's letter (HARNESS.md 1.7).
OPERATIONS: dict[str, tuple[str, str]] = {
    "EC": ("2|1.arm", "C2.1-C1.1 (two combs, connector end first) or C1.1.L (a comb, the arm)"),
    "PC": ("1", "J8.1.L (guide, then L or R for the arm)"),
    "RC": ("1+", "J3.1-J4.1 (guides in routing order)"),
    "T": ("3", "J1.1-J2.1-J2.1 (the two guides to tape between, then the one to hold beside)"),
    "TJ": ("1", "J1.1"),
}
# What REMODEL parses but never executes: refused at its row rather than guessed at.
UNEXECUTED = {
    "TJ": "TJ (taping in a jig) is parsed but never executed by REMODEL's planner (it has no "
    "handler for it, HARNESS.md 1.7); the import does not guess what it means: remove the "
    "row, or write a T row (J1.1-J2.1-J2.1)",
}

# Required columns as REMODEL spells them; matched ignoring case and extra spaces.
COMPONENT_COLUMNS = ("Type", "Model", "Label", "length", "Diameter", "x", "y", "z")
SEQUENCE_COLUMNS = ("Order", "Type of operation", "Label", "Spot")

# Names become YAML keys and parts of dotted plan references (see cellengine.info.cell).
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]*$")
_INT = re.compile(r"^[+-]?\d{1,9}$")  # an Order: a sequence is never a billion rows long


# --- reading ;-separated tables ----------------------------------------------------------


@dataclass(frozen=True)
class Table:
    """A CSV with its header: ``columns`` maps a normalised header name to its first index
    (REMODEL's components header has 'Type' twice; the first is the component type)."""

    file: Path
    header: tuple[str, ...]
    columns: Mapping[str, int]
    rows: tuple[tuple[int, tuple[str, ...]], ...]

    def cell(self, cells: Sequence[str], column: str) -> str:
        i = self.columns.get(_norm(column))
        return cells[i].strip() if i is not None else ""


def _norm(name: str) -> str:
    return " ".join(name.split()).lower()


def read_table(path: Path, required: Sequence[str]) -> Table:
    """Header and data rows of a ``;``-separated file. A missing column is an error at
    the header; a row with another number of cells than the header, at that row."""
    records = _records(path)
    first = next(records, None)
    wanted = ", ".join(required)
    if first is None:
        raise InputError.at(f"empty file; expected a ';'-separated header with {wanted}", path, 1)
    header_row, header = first
    columns: dict[str, int] = {}
    for i, name in enumerate(header):
        columns.setdefault(_norm(name), i)
    missing = [c for c in required if _norm(c) not in columns]
    if missing:
        has = ", ".join(h.strip() for h in header)
        raise InputError.at(
            f"missing column {', '.join(repr(m) for m in missing)}; the header has: {has}"
            + (" (is the file ';'-separated?)" if len(header) == 1 else ""),
            path,
            header_row,
        )
    rows: list[tuple[int, tuple[str, ...]]] = []
    problems: list[Problem] = []
    for row, cells in records:
        if len(cells) != len(header):
            msg = f"expected {len(header)} ';'-separated cells as in the header, found {len(cells)}"
            problems.append(Problem(msg, str(path), row))
        else:
            rows.append((row, tuple(cells)))
    if problems:
        raise InputError(problems)
    return Table(path, tuple(header), columns, tuple(rows))


def _decode(raw: bytes, path: Path) -> str:
    try:
        return raw.decode("utf-8-sig")  # spreadsheets write a BOM
    except UnicodeDecodeError:
        pass
    try:
        # Excel's "CSV (semicolon)" on Windows writes the ANSI code page, not UTF-8.
        return raw.decode("cp1252")
    except UnicodeDecodeError as e:
        line = raw.count(b"\n", 0, e.start) + 1
        raise InputError.at("file is neither UTF-8 nor Windows-1252 text", path, line) from None


def _records(path: Path) -> Iterator[tuple[int, list[str]]]:
    """Non-blank records with the line they start on (a quoted cell may span lines)."""
    text = _decode(read_capped(path, "csv"), path)
    yield from records(text, path, SEP)


def _parse_rows(table: Table, parse: Callable[[Table, Sequence[str], int], T]) -> list[T]:
    """``parse`` of every row; every bad row is reported, not just the first."""
    out: list[T] = []
    problems: list[Problem] = []
    for row, cells in table.rows:
        try:
            out.append(parse(table, cells, row))
        except InputError as e:
            problems.extend(e.problems)
    if problems:
        raise InputError(problems)
    return out


def _unique(
    items: Sequence[T], key: Callable[[T], object], what: str, path: Path, row: Callable[[T], int]
) -> None:
    first: dict[object, int] = {}
    problems: list[Problem] = []
    for item in items:
        k = key(item)
        if k in first:
            msg = f"duplicate {what} {k} (first used in row {first[k]})"
            problems.append(Problem(msg, str(path), row(item)))
        else:
            first[k] = row(item)
    if problems:
        raise InputError(problems)


def number(text: str, what: str, path: Path, row: int) -> Number:
    """A positive number; a decimal comma is read as a point (the separator is ';')."""
    if not text:
        raise InputError.at(f"empty {what}", path, row)
    t = text.replace(",", ".")
    try:
        value: Number = int(t) if _INT.match(t) else float(t)
    except ValueError:
        raise InputError.at(f"{what} '{text}' is not a number", path, row) from None
    if not math.isfinite(value) or value <= 0:
        raise InputError.at(f"{what} must be greater than 0, got {text}", path, row)
    return value


def _name(text: str, what: str, path: Path, row: int) -> str:
    if not text:
        raise InputError.at(f"empty {what}", path, row)
    if not _NAME.match(text):
        raise InputError.at(
            f"{what} '{text}' is not a valid name: use letters, digits, '_' and '-', "
            "starting with a letter or '_'",
            path,
            row,
        )
    return text


# --- Components_definition.csv -----------------------------------------------------------


@dataclass(frozen=True)
class ConnectorRow:
    """A connector; sizes in the file's mm. The CSV's x, y, z are the connector's CAD box:
    x across its wide face (width), y its thickness (height) and z along the cable (length)
    — a VGA connector with its hood is about 31 x 16 x 45 mm, as in the sample."""

    label: str
    type: str  # the Model column, e.g. VGA
    length: Number  # z
    width: Number  # x
    height: Number  # y
    color: str
    row: int


@dataclass(frozen=True)
class CableRow:
    label: str
    length: Number  # mm
    diameter: Number  # mm
    color: str
    row: int


@dataclass(frozen=True)
class Components:
    file: Path
    connectors: Mapping[str, ConnectorRow]
    cables: Mapping[str, CableRow]

    def labels(self) -> list[str]:
        return [*self.connectors, *self.cables]


def load_components(path: Path) -> Components:
    table = read_table(path, COMPONENT_COLUMNS)
    items = _parse_rows(table, _component)
    _unique(items, lambda c: f"'{c.label}'", "Label", path, lambda c: c.row)
    return Components(
        path,
        {c.label: c for c in items if isinstance(c, ConnectorRow)},
        {c.label: c for c in items if isinstance(c, CableRow)},
    )


def _component(table: Table, cells: Sequence[str], row: int) -> ConnectorRow | CableRow:
    path = table.file
    kind = table.cell(cells, "type")
    label = _name(table.cell(cells, "label"), "Label", path, row)
    color = table.cell(cells, "color")
    if kind.lower() == "cable":
        return CableRow(
            label,
            number(table.cell(cells, "length"), f"length of cable {label}", path, row),
            number(table.cell(cells, "diameter"), f"Diameter of cable {label}", path, row),
            color,
            row,
        )
    if kind.lower() == "connector":
        model = table.cell(cells, "model")
        if not model:
            raise InputError.at(f"empty Model (the type) of connector {label}", path, row)

        def size(column: str) -> Number:
            return number(table.cell(cells, column), f"{column} of connector {label}", path, row)

        return ConnectorRow(label, model, size("z"), size("x"), size("y"), color, row)
    raise InputError.at(
        f"unknown component type '{kind}'" + known(["Cable", "Connector"]), path, row
    )


# --- Assembly_sequence.csv ---------------------------------------------------------------


@dataclass(frozen=True)
class Spot:
    """One guide named in a Spot: element label, guide index (``couple``), and for PC
    the arm (a robot name from :data:`ARMS`)."""

    element: str
    couple: str
    arm: str | None = None


@dataclass(frozen=True)
class Operation:
    order: int
    kind: str  # EC | PC | RC | T
    label: str  # a connector (or cable) label of the components file, or a branch's (RC)
    spot: str  # as written, for messages
    spots: tuple[Spot, ...]
    row: int


def load_sequence(path: Path, warnings: list[Problem] | None = None) -> tuple[Operation, ...]:
    """Operations in file order, as REMODEL runs them: it ignores the Order column, so an
    Order out of step with the rows is a warning (appended to ``warnings``), not a sort."""
    table = read_table(path, SEQUENCE_COLUMNS)
    ops = _parse_rows(table, _operation)
    if warnings is not None:
        warnings += _order_warnings(table, ops, path)
    return tuple(ops)


def _order_warnings(table: Table, ops: Sequence[Operation], path: Path) -> list[Problem]:
    out: list[Problem] = []
    for before, op in itertools.pairwise(ops):
        if op.order <= before.order:
            msg = (
                f"Order {op.order} comes after Order {before.order} (row {before.row}): "
                "REMODEL ignores the Order column and runs the rows in file order; so does the "
                "import"
            )
            out.append(Problem(msg, str(path), op.row))
    for row, cells in table.rows:
        kind = table.cell(cells, "type of operation")
        if kind != kind.upper():
            msg = (
                f"operation '{kind}' is read as {kind.upper()}; REMODEL's planner compares "
                "operation types case-sensitively and would not run it"
            )
            out.append(Problem(msg, str(path), row))
    return out


def _operation(table: Table, cells: Sequence[str], row: int) -> Operation:
    path = table.file
    order_text = table.cell(cells, "order")
    if not _INT.match(order_text):
        shown = order_text if len(order_text) <= 20 else order_text[:20] + "..."
        raise InputError.at(
            f"Order '{shown}' is not a whole number (of at most 9 digits)", path, row
        )
    kind = table.cell(cells, "type of operation")
    if kind.upper() not in OPERATIONS:
        raise InputError.at(f"unknown operation '{kind}'" + known(OPERATIONS), path, row)
    kind = kind.upper()
    if kind in UNEXECUTED:
        raise InputError.at(UNEXECUTED[kind], path, row)
    label = _name(table.cell(cells, "label"), "Label", path, row)
    spot = table.cell(cells, "spot")
    return Operation(int(order_text), kind, label, spot, parse_spot(kind, spot, path, row), row)


def parse_spot(kind: str, spot: str, path: Path, row: int) -> tuple[Spot, ...]:
    """``C2.1-C1.1`` -> C2/1 and C1/1; ``J8.1.L`` (PC, and EC's one-comb form) -> J8/1, arm
    left; ``J1.1-J2.1-J2.1`` (T) -> three guides."""
    count, example = OPERATIONS[kind]
    if not spot:
        raise InputError.at(f"empty Spot; {kind} writes e.g. {example}", path, row)
    spots = tuple(_spot_item(kind, item.strip(), spot, path, row) for item in spot.split("-"))
    armed = [s for s in spots if s.arm is not None]
    n = len(spots)
    expected = {
        "1": n == 1,
        "3": n == 3,
        "1+": n >= 1,
        "2|1.arm": (n == 2 and not armed) or (n == 1 and bool(armed)),
    }[count]
    if not expected:
        what = {"2|1.arm": "2 combs, or 1 comb with an arm", "1+": "1 or more guides"}
        names = what.get(count, f"{count} guide{'s' if count != '1' else ''}")
        written = f"{n}" + (" with an arm" if armed else "") if count == "2|1.arm" else f"{n}"
        raise InputError.at(
            f"{kind} names {names}, e.g. {example}; '{spot}' names {written}", path, row
        )
    return spots


def _spot_item(kind: str, item: str, spot: str, path: Path, row: int) -> Spot:
    parts = [p.strip() for p in item.split(".")]
    where = f" in Spot '{spot}'" if item != spot else ""
    armed = kind in ("PC", "EC")
    if len(parts) not in (2, 3) or not all(parts):
        raise InputError.at(
            f"'{item}'{where} is not element.guide (e.g. J3.1)"
            + (" or element.guide.arm (e.g. J8.1.L)" if armed else ""),
            path,
            row,
        )
    element, couple = parts[0], parts[1]
    if not couple.isdigit():
        raise InputError.at(f"guide '{couple}' of '{item}'{where} is not a number", path, row)
    if len(parts) == 2:
        return Spot(element, couple)
    if not armed:
        raise InputError.at(
            f"'{item}'{where}: only PC and EC spots name an arm; {kind} writes e.g. "
            + OPERATIONS[kind][1],
            path,
            row,
        )
    letter = parts[2]
    if letter.upper() not in ARMS:
        raise InputError.at(
            f"unknown arm letter '{letter}' in '{item}'" + known(ARMS) + " (left, right)",
            path,
            row,
        )
    return Spot(element, couple, ARMS[letter.upper()])
