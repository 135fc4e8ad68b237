"""One localisation as the commands use it: the cell's camera, a picture, the containers
found, and what to do with them (a table, JSON, objects.yaml's `at` values)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from cellengine.errors import InputError, printable
from cellengine.info.camera import Camera
from cellengine.info.objects import Objects
from cellengine.locate import image as pictures
from cellengine.locate.extrinsics import PoseError
from cellengine.locate.objects import Located, locate
from cellengine.locate.rewrite import at_text
from cellengine.world import World


def camera_of(world: World) -> Camera:
    if world.cell.camera is None:
        raise InputError.at(
            "the cell has no camera: add `camera` (resolution, matrix, distortion, marker, "
            "world markers) to locate objects",
            world.cell_file,
        )
    return world.cell.camera


def located(world: World, image: Path | None, device: int | None) -> Located:
    camera = camera_of(world)
    if not any(c.marker is not None for c in world.objects.containers.values()):
        raise InputError.at("no container has a `marker`: nothing to locate", world.cell_file)
    source: Path | str = image if image is not None else f"camera {device}"
    if image is not None:
        picture = pictures.from_file(image, camera)
    else:
        assert device is not None
        picture = pictures.from_device(device, camera)
    try:
        return locate(world, camera, picture)
    except PoseError as e:
        raise InputError.at(f"no camera pose: {e}", source) from None


def at_values(world: World, found: Located) -> dict[str, str]:
    """Each located container's new `at`, as written in objects.yaml."""
    return {
        f.name: at_text(f, world.objects, world.container(f.name).kind == "box")
        for f in found.found
    }


def at_settings(world: World, found: Located) -> dict[str, Any]:
    """Each located container's `at` as a value set over objects.yaml (a keypoint, or a
    pose in the file's units)."""
    out: dict[str, Any] = {}
    units = _units(world.objects)
    for f in found.found:
        if f.keypoint is not None:
            out[f.name] = f.keypoint
            continue
        value: dict[str, Any] = {"xyz": [float(v) / units[0] for v in f.xyz]}
        if world.container(f.name).kind == "box":
            value["rpy"] = [0.0, 0.0, f.yaw / units[1]]
        out[f.name] = value
    return out


def table(world: World, found: Located) -> list[str]:
    pose = found.pose
    x, y, z = (v * 1000.0 for v in pose.T_cell_camera[:3, 3])
    used = ", ".join(str(m) for m in pose.used)
    lines = [
        f"camera at x {x:.1f} y {y:.1f} z {z:.1f} mm, from world markers {used} "
        f"({pose.rms:.2f} px RMS)"
    ]
    if found.found:
        width = max(len("object"), *(len(printable(f.name)) for f in found.found))
        lines.append(f"{'object':<{width}}  marker     x mm     y mm     z mm  yaw deg  stands at")
        for f in found.found:
            where = f"{f.keypoint} ({f.off * 1000:.1f} mm off)" if f.keypoint else "the table"
            lines.append(
                f"{printable(f.name):<{width}}  {f.marker:>6}  "
                + "  ".join(f"{v * 1000.0:7.1f}" for v in f.xyz)
                + f"  {math.degrees(f.yaw):7.1f}  {where}"
            )
    for name in found.unseen:
        c = world.container(name)
        kept = f"objects.yaml's place kept ({c.at})" if isinstance(c.at, str) else "not placed"
        lines.append(f"not seen: {printable(name)} (marker {c.marker}): {kept}")
    if found.strangers:
        lines.append(
            "markers seen that are neither a world marker nor a container's: "
            + ", ".join(str(m) for m in found.strangers)
        )
    if found.twice:
        lines.append(
            "markers seen more than once (not used): " + ", ".join(str(m) for m in found.twice)
        )
    return lines


def as_json(found: Located) -> dict[str, Any]:
    T = found.pose.T_cell_camera
    return {
        "camera": {
            "T_cell_camera": [[round(float(v), 9) for v in row] for row in T],
            "world_markers": list(found.pose.used),
            "rms_px": round(found.pose.rms, 4),
        },
        "found": {
            f.name: {
                "marker": f.marker,
                "xyz": [round(float(v), 9) for v in f.xyz],
                "yaw": round(f.yaw, 9),
                "keypoint": f.keypoint,
                "off": round(f.off, 9) if f.keypoint else None,
            }
            for f in found.found
        },
        "unseen": list(found.unseen),
        "strangers": list(found.strangers),
        "twice": list(found.twice),
    }


def _units(objects: Objects) -> tuple[float, float]:
    from cellengine.info.units import ANGLE, LENGTH

    return LENGTH[objects.units.length], ANGLE[objects.units.angle]
