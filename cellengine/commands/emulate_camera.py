"""`cellengine emulate camera CELL --out FILE [--objects F] [--move NAME=X,Y[,YAW]] ...`:
the picture the cell's camera would take of the bench (cellengine/emulate/camera.py), for
trying `cellengine locate` without a camera."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from cellengine.errors import EXIT_OK, InputError, UsageError


def add_camera(kinds: Any) -> None:
    p = kinds.add_parser(
        "camera",
        help="a picture of the bench from the cell's camera",
        description="Write the picture the cell's camera (cell.yaml `camera`) would take "
        "from above the world markers' middle: the world markers, and the containers of "
        "objects.yaml where they stand (or where --move puts them) with their markers, "
        "through the camera's lens, blurred and noisy.",
    )
    p.add_argument("cell", type=Path, metavar="CELL", help="a cell.yaml, or its folder")
    p.add_argument("--out", type=Path, required=True, metavar="FILE", help="the picture (.png)")
    p.add_argument(
        "--objects", type=Path, metavar="FILE", help="objects.yaml (default: the cell folder's)"
    )
    p.add_argument(
        "--move",
        action="append",
        default=[],
        metavar="NAME=X,Y[,YAW]",
        help="stand container NAME on the table at X, Y (mm), turned YAW deg",
    )
    p.add_argument("--height", type=float, default=900.0, help="camera height, mm (900)")
    p.add_argument("--seed", type=int, default=0, help="the noise's seed")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import cv2
    import numpy as np

    from cellengine import geometry
    from cellengine.emulate.camera import Shot, looking_down, render, solids, world_markers
    from cellengine.info.load import load_world
    from cellengine.locate.session import camera_of

    cell: Path = args.cell / "cell.yaml" if args.cell.is_dir() else args.cell
    objects: Path = args.objects or cell.parent / "objects.yaml"
    world = load_world(cell, objects if objects.exists() else None)
    camera = camera_of(world)
    moved = {}
    for text in args.move:
        name, _, where = text.partition("=")
        if name not in world.objects.containers:
            _unknown(name, world)
        try:
            values = [float(v) for v in where.split(",")]
        except ValueError:
            values = []
        if len(values) not in (2, 3):
            raise UsageError.at(f"--move {text}: write NAME=X,Y or NAME=X,Y,YAW (mm, deg)", None)
        yaw = math.radians(values[2]) if len(values) == 3 else 0.0
        at = (values[0] / 1000.0, values[1] / 1000.0, camera.table)
        moved[name] = geometry.pose(at, (0.0, 0.0, yaw))
    middle = np.mean([p.matrix()[:2, 3] for p in camera.world.values()], axis=0)
    T = looking_down(float(middle[0]), float(middle[1]), args.height / 1000.0, math.pi / 2)
    image = render(camera, Shot(T, world_markers(camera), solids(world, moved), seed=args.seed))
    if not cv2.imwrite(str(args.out), image):
        raise InputError.at("cannot write the picture (a .png or .jpg name?)", args.out)
    print(f"wrote {args.out}")
    return EXIT_OK


def _unknown(name: str, world: Any) -> None:
    from cellengine.errors import known

    raise UsageError.at(
        f"--move: unknown container '{name}'" + known(world.objects.containers), None
    )
