"""`cellengine show CELL [--json]`: every keypoint in the cell frame."""

from __future__ import annotations

import argparse
import json
import math
import os
from pathlib import Path
from typing import Any

from cellengine.errors import EXIT_OK, UsageError, printable
from cellengine.geometry import xyz_rpy
from cellengine.info.load import load_world


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="print every keypoint of a cell in the cell frame",
        description="Print every keypoint in the cell frame: a table with xyz "
        "in mm and rpy in deg, or JSON in metres and radians.",
    )
    p.add_argument("cell", type=Path, metavar="CELL", help="a cell.yaml, or its folder")
    p.add_argument("--json", action="store_true", help="print JSON (metres, radians)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    path: Path = args.cell
    if path.is_dir():
        path = path / "cell.yaml"
    if not os.path.lexists(path):  # there but not a file: the loader names what it is
        raise UsageError.at("no such cell file", path)
    world = load_world(path)
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
