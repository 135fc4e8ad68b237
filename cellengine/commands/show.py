"""`cellengine show CELL [--json | --html [OUT]]`: every keypoint in the cell frame, or the
cell page (cellengine/report/cell_page.py): the cell at home, its keypoints coloured by the
arms that reach them."""

from __future__ import annotations

import argparse
import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any

from cellengine.errors import EXIT_OK, InputError, UsageError, display_path, printable
from cellengine.geometry import xyz_rpy
from cellengine.info.load import load_world
from cellengine.world import World

PAGE = object()  # --html without a path: CELLNAME.html in the working folder


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="print every keypoint of a cell in the cell frame, or write the cell page",
        description="Print every keypoint in the cell frame: a table with xyz "
        "in mm and rpy in deg, or JSON in metres and radians; or write the cell page "
        "(--html): the robots at home and each keypoint coloured by the arms that reach it.",
    )
    p.add_argument("cell", type=Path, metavar="CELL", help="a cell.yaml, or its folder")
    out = p.add_mutually_exclusive_group()
    out.add_argument("--json", action="store_true", help="print JSON (metres, radians)")
    out.add_argument(
        "--html",
        nargs="?",
        const=PAGE,
        type=Path,
        metavar="OUT",
        help="write the cell page: robots at home, keypoints labelled and coloured by the "
        "arms that reach them (default OUT: CELLNAME.html here)",
    )
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    path: Path = args.cell
    if path.is_dir():
        path = path / "cell.yaml"
    if not os.path.lexists(path):  # there but not a file: the loader names what it is
        raise UsageError.at("no such cell file", path)
    world = load_world(path)
    if args.html is not None:
        out = Path(f"{world.cell.name}.html") if args.html is PAGE else args.html
        return write_page(world, out)
    rows = {name: xyz_rpy(T) for name, T in world.keypoints().items()}
    if args.json:
        out = {
            n: {"xyz": [round(float(v), 9) for v in xyz], "rpy": [round(float(v), 9) for v in rpy]}
            for n, (xyz, rpy) in rows.items()
        }
        print(json.dumps({"keypoints": out}, indent=2))
        return EXIT_OK
    shown = {name: printable(name) for name in rows}  # names from files; JSON escapes its own
    width = max([len("keypoint"), *map(len, shown.values())])
    head = ["x mm", "y mm", "z mm", "roll deg", "pitch deg", "yaw deg"]
    print(f"{'keypoint':<{width}}  " + "  ".join(f"{h:>9}" for h in head))
    for name, (xyz, rpy) in rows.items():
        degrees = [math.degrees(v) for v in rpy]
        degrees = [180.0 if round(d, 2) == -180.0 else d for d in degrees]  # one way to say it
        values = [*(v * 1000.0 for v in xyz), *degrees]
        # round, then + 0.0 turns -0.0 into 0.0: the table never shows "-0.00"
        print(f"{shown[name]:<{width}}  " + "  ".join(f"{round(v, 2) + 0.0:9.2f}" for v in values))
    return EXIT_OK


def write_page(world: World, out: Path) -> int:
    """Write the cell page to ``out`` and say what reaches what."""
    # the motion stack is imported when a page is asked for, not for the table
    from cellengine.motion.robot import build_cell_model
    from cellengine.reach import keypoint_reach
    from cellengine.report.cell_page import cell_page

    cell = build_cell_model(world)
    reach = keypoint_reach(world, cell)
    write_text(out, cell_page(world, cell, reach))
    print(printable(f"{display_path(out)}: {reach_summary(reach, list(cell.arms))}"))
    return EXIT_OK


def reach_summary(reach: dict[str, tuple[str, ...]], arms: list[str]) -> str:
    """'15 keypoints: 12 reached by every arm, 3 by left only' (the classes the page colours)."""

    def what(reached: tuple[str, ...]) -> str:
        if not reached:
            return "no arm"
        if len(reached) == len(arms):
            return "every arm"
        return f"{reached[0]} only" if len(reached) == 1 else ", ".join(reached)

    def rank(reached: tuple[str, ...]) -> tuple[int, int, list[int]]:
        # every arm first, then one arm, then several, in the cell's order; no arm last
        return (len(reached) != len(arms), not reached, [arms.index(a) for a in reached])

    order = sorted(set(reach.values()), key=rank)
    counts = {r: sum(1 for v in reach.values() if v == r) for r in order}
    parts = [f"{n} by {what(r)}" for r, n in counts.items()]
    if parts:
        parts[0] = parts[0].replace(" by ", " reached by ", 1)
    return f"{len(reach)} keypoints" + (": " + ", ".join(parts) if parts else "")


def write_text(path: Path, text: str, what: str = "the cell page") -> None:
    """``path``'s new content, whole or not at all: a temporary file beside it, renamed over
    it (which replaces a link rather than writing through it)."""
    folder = path.parent
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
        try:
            with os.fdopen(fd, "w", encoding="utf-8") as f:
                f.write(text)
            os.chmod(tmp, 0o644)  # mkstemp's 0600 would keep the page from others
            os.replace(tmp, path)
        except BaseException:
            os.unlink(tmp)
            raise
    except OSError as e:
        raise InputError.at(f"cannot write {what}: {e.strerror}", path) from None
