"""CSV records with the line each starts on, for errors at file:row."""

from __future__ import annotations

import csv
import io
from collections.abc import Iterator
from pathlib import Path

from cellengine.errors import InputError


def records(text: str, path: Path, delimiter: str = ",") -> Iterator[tuple[int, list[str]]]:
    """Non-blank records with the line they start on (a quoted cell may span lines)."""
    reader = csv.reader(io.StringIO(text, newline=""), delimiter=delimiter, strict=True)
    line = 1
    while True:
        try:
            cells = next(reader)
        except StopIteration:
            return
        except csv.Error as e:
            raise InputError.at(f"malformed CSV: {e}", path, line) from None
        if any(c.strip() for c in cells):
            yield line, cells
        line = reader.line_num + 1
