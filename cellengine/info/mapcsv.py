"""The mapping CSV of a native platform (DESIGN 3.2): each row relates an X3D ``DEF`` to its
element model and gives the element the name plans use.

```
cad_name,model,name
ID0004,guide_u,guide1
Plate,obstacle,plate
Label,ignore,label
```

Rows are CSV line numbers (the header is row 1), so errors point where an editor does.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from cellengine.errors import InputError
from cellengine.info.csvrows import records
from cellengine.info.files import read_capped

HEADER = ("cad_name", "model", "name")
# models that are words of the map (native.py): the part is an obstacle, or not one
OBSTACLE, IGNORE = "obstacle", "ignore"


@dataclass(frozen=True)
class MapRow:
    cad_name: str
    model: str
    name: str
    row: int  # CSV line number, for errors found later (unknown CAD name or model)


def load_map(path: Path) -> tuple[MapRow, ...]:
    rows = _rows(path)
    header = next(rows, None)
    if header is None:
        raise InputError.at(f"empty mapping file; expected the header {','.join(HEADER)}", path, 1)
    row, cells = header
    if tuple(c.strip() for c in cells) != HEADER:
        raise InputError.at(
            f"header is '{','.join(cells)}'; expected exactly '{','.join(HEADER)}'", path, row
        )
    out: list[MapRow] = []
    first_cad: dict[str, int] = {}
    first_name: dict[str, int] = {}
    for row, cells in rows:
        entry = _entry(cells, path, row)
        _unique(entry.cad_name, "cad_name", first_cad, path, row)
        _unique(entry.name, "name", first_name, path, row)
        out.append(entry)
    return tuple(out)


def _rows(path: Path) -> Iterator[tuple[int, list[str]]]:
    """Non-blank records with the line they start on."""
    raw = read_capped(path, "csv")
    try:
        text = raw.decode("utf-8-sig")  # spreadsheets write a BOM
    except UnicodeDecodeError as e:
        raise InputError.at(
            "file is not valid UTF-8", path, raw.count(b"\n", 0, e.start) + 1
        ) from None
    yield from records(text, path)


def _entry(cells: list[str], path: Path, row: int) -> MapRow:
    if len(cells) != len(HEADER):
        raise InputError.at(
            f"expected {len(HEADER)} columns ({','.join(HEADER)}), found {len(cells)}", path, row
        )
    values = [c.strip() for c in cells]
    for column, value in zip(HEADER, values, strict=True):
        if not value:
            raise InputError.at(f"empty {column}", path, row)
    cad_name, model, name = values
    if "." in name or any(ch.isspace() for ch in name):
        raise InputError.at(
            f"name '{name}' may not contain dots or spaces (plans write platform.element.keypoint)",
            path,
            row,
        )
    return MapRow(cad_name, model, name, row)


def _unique(value: str, column: str, first: dict[str, int], path: Path, row: int) -> None:
    if value in first:
        raise InputError.at(
            f"duplicate {column} '{value}' (first used in row {first[value]})", path, row
        )
    first[value] = row
