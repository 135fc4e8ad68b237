"""`cellengine locate CELL (--image FILE | --camera N) [--objects F] [--out F] [--json]`:
where the camera finds each container by the ArUco marker on its top (paper 004, II-C),
printed, or as a copy of objects.yaml with their places (--out)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from cellengine.errors import EXIT_OK, InputError, UsageError
from cellengine.info.load import load_objects, load_world
from cellengine.info.yamlio import load_yaml


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="locate the containers on the bench by their ArUco markers",
        description="Find the camera's pose from cell.yaml's world markers, then each "
        "container of objects.yaml by the marker on its top; print where each stands, or "
        "write a copy of objects.yaml with their places (--out).",
    )
    p.add_argument("cell", type=Path, metavar="CELL", help="a cell.yaml, or its folder")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--image", type=Path, metavar="FILE", help="a picture from the camera")
    source.add_argument("--camera", type=int, metavar="N", help="take one from video device N")
    p.add_argument(
        "--objects", type=Path, metavar="FILE", help="objects.yaml (default: the cell folder's)"
    )
    p.add_argument("--out", type=Path, metavar="FILE", help="write objects.yaml's copy here")
    p.add_argument("--json", action="store_true", help="print JSON (metres, radians)")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from cellengine.locate.session import as_json, at_values, located, table

    cell: Path = args.cell / "cell.yaml" if args.cell.is_dir() else args.cell
    objects: Path = args.objects or cell.parent / "objects.yaml"
    for path, what in ((cell, "cell"), (objects, "objects")):
        if not path.exists():
            raise UsageError.at(f"no such {what} file", path)
    world = load_world(cell, objects)
    found = located(world, args.image, args.camera)
    if args.out is not None:
        write_copy(objects, at_values(world, found), args.out)
    if args.json:
        print(json.dumps(as_json(found), indent=2))
    else:
        print("\n".join(table(world, found)))
        if args.out is not None:
            print(f"wrote {args.out}: {len(found.found)} containers' places")
    return EXIT_OK


def write_copy(objects: Path, values: dict[str, str], out: Path) -> None:
    """objects.yaml with the new `at` values, checked as a file of its own (it loads and its
    keypoints resolve with the cell) before it is written, whole or not at all."""
    import tempfile

    from cellengine.commands.show import write_text
    from cellengine.locate.rewrite import rewritten

    text = objects.read_text(encoding="utf-8")
    try:
        new = rewritten(text, load_yaml(objects), values)
    except ValueError as e:
        raise InputError.at(
            f"cannot rewrite `at` here ({e}); write it on one line", objects
        ) from None
    with tempfile.TemporaryDirectory() as tmp:
        check = Path(tmp) / objects.name
        check.write_text(new, encoding="utf-8")
        load_objects(check)
    write_text(out, new, "the objects' copy")
