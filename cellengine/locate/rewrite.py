"""A copy of objects.yaml with the containers' `at` where the camera found them: the file's
own text edited in place (comments, order and style kept), each located container's `at`
replaced or added."""

from __future__ import annotations

from cellengine.info.objects import Objects
from cellengine.info.units import ANGLE, LENGTH
from cellengine.info.yamlio import YamlDoc
from cellengine.locate.objects import Found


def at_text(found: Found, objects: Objects, box: bool) -> str:
    """``found`` as an `at` value: its keypoint, or a flow pose in the file's units."""
    if found.keypoint is not None:
        return found.keypoint
    unit = LENGTH[objects.units.length]
    # to 0.01 mm in the file's unit (m: 5 decimals), trailing zeros dropped
    digits = {"mm": 2, "cm": 3, "m": 5}[objects.units.length]
    xyz = ", ".join(_number(v / unit, digits) for v in found.xyz)
    if not box:
        return f"{{xyz: [{xyz}]}}"
    yaw = _number(found.yaw / ANGLE[objects.units.angle], 4)
    return f"{{xyz: [{xyz}], rpy: [0, 0, {yaw}]}}"


def _number(value: float, digits: int) -> str:
    text = f"{round(value, digits) + 0.0:.{digits}f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def rewritten(text: str, doc: YamlDoc, values: dict[str, str]) -> str:
    """``text`` (``doc``'s) with containers.NAME.at set to ``values[NAME]``."""
    lines = text.splitlines(keepends=True)
    # from the end of the file up, so that each edit leaves the places before it as they are
    edits = sorted(((_place(doc, lines, name), name) for name in values), reverse=True)
    for (line, col, end, insert), name in edits:
        row = lines[line]
        value = values[name]
        if insert == "flow":
            new = f"at: {value}, "
        elif insert == "block":
            new = f"at: {value}\n" + " " * col
        else:
            new = value
        lines[line] = row[:col] + new + row[end:]
    return "".join(lines)


def _place(doc: YamlDoc, lines: list[str], name: str) -> tuple[int, int, int, str]:
    """Where the new value goes: line, column (0-based), the end of what it replaces on
    that line, and how (replace, or insert into a flow or block mapping)."""
    loc = ("containers", name, "at")
    if loc in doc.values:
        line, col = (v - 1 for v in doc.values[loc])
        if isinstance(doc.data["containers"][name]["at"], dict) and lines[line][col] != "{":
            raise ValueError(f"line {line + 1}: containers.{name}.at is a block mapping")
        return line, col, col + _length(lines[line], col, lines, line), "replace"
    line, col = (v - 1 for v in doc.values[loc[:2]])
    if lines[line][col] == "{":
        return line, col + 1, col + 1, "flow"
    return line, col, col, "block"


def _length(row: str, col: int, lines: list[str], line: int) -> int:
    """The length of the value at ``col``: a plain or quoted scalar, or a flow mapping on
    one line."""
    first = row[col]
    if first in "\"'":
        end = row.find(first, col + 1)
        if end < 0:
            raise ValueError(f"line {line + 1}: a quoted `at` over several lines")
        return end + 1 - col
    if first == "{":
        depth = 0
        for i in range(col, len(row)):
            depth += {"{": 1, "}": -1}.get(row[i], 0)
            if depth == 0:
                return i + 1 - col
        raise ValueError(f"line {line + 1}: an `at` over several lines")
    stop = len(row.rstrip("\n"))
    for i in range(col, len(row)):
        if row[i] in ",}" or row[i : i + 2] == " #":
            stop = i
            break
    return len(row[col:stop].rstrip())
