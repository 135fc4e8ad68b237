"""Small builders shared by tests: a world with hand-made platforms (no files)."""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np

from cellengine import geometry as g
from cellengine.info.cell import Cell
from cellengine.info.objects import Objects
from cellengine.info.platform import Element, Keypoint, Platform
from cellengine.world import World

if TYPE_CHECKING:
    from cellengine.drivers.sim import SimDriver
    from cellengine.pipeline import Compiled


def element(
    name: str,
    xyz: tuple[float, float, float],
    keypoints: dict[str, g.Mat],
    dims: dict[str, float] | None = None,
    note: str = "",
) -> Element:
    return Element(
        name=name,
        model="m",
        T_platform_element=g.pose(xyz),
        dimensions=MappingProxyType(dims or {}),
        keypoints=MappingProxyType({k: Keypoint(k, T) for k, T in keypoints.items()}),
        note=note,
    )


def routing_world() -> World:
    """Platform 'routing' at (0.5, -0.1, 0) turned 90 deg about z, with three guides."""
    slot = g.pose([0.0, 0.0, 0.055])
    guides = {
        f"guide{i}": element(
            f"guide{i}",
            (0.1 * i, 0.0, 0.0),
            {"slot": slot, "top": np.eye(4)},
            {"length": 0.01, "gap": 0.01},
        )
        for i in (1, 2, 3)
    }
    guides["plate"] = element("plate", (0, 0, 0), {}, note="model 'x' is not defined")
    platform = Platform(
        "routing", g.pose([0.5, -0.1, 0.0], [0, 0, np.pi / 2]), MappingProxyType(guides)
    )
    cell = Cell.model_validate(
        {"name": "c", "robots": {"left": {"model": "ur5e"}, "right": {"model": "ur5e"}}}
    )
    objects = Objects.model_validate(
        {
            "cables": {"cable1": {"length": 0.65, "diameter": 0.006}},
            "containers": {"vial1": {"kind": "vial", "diameter": 0.028, "height": 0.06}},
        }
    )
    return World(cell, Path_("cell.yaml"), MappingProxyType({"routing": platform}), objects)


def Path_(p: str):
    from pathlib import Path

    return Path(p)


# A wall across the lab bench at x = 880 mm, between the shared racks (x 400) and the free
# places (x 1000), up to 380 mm: no robot gets a vial past it (robot1's home, x 750, is clear).
WALL = "  wall: {box: [20, 1300, 360], pose: {xyz: [880, 650, 200]}}\n"


def walled_lab(folder: Path) -> Path:
    """The lab bench copied into ``folder`` with the wall above in cell.yaml: its
    plan_relocate.yaml (returned) fails to compile in ~3 s, robot2 finding no transit to carry
    vial5 past the wall, after the 3 segments that pick it."""
    import shutil

    from tests.conftest import CELLS

    shutil.copytree(CELLS / "lab_bench", folder)
    cell = folder / "cell.yaml"
    text = cell.read_text()
    table = next(line for line in text.splitlines(keepends=True) if line.startswith("  table:"))
    cell.write_text(text.replace(table, table + WALL, 1))
    return folder / "plan_relocate.yaml"


def vial1_heavier_sim(compiled: Compiled) -> SimDriver:
    """The simulated cell of a compiled lab plan, at its first pose, whose load cell weighs
    vial1 at 50 g (objects.yaml says vial2 is the heavier): a run that weighs replans."""
    from cellengine.drivers.sim import SimDriver

    objects = compiled.world.objects
    heavy = objects.containers["vial1"].model_copy(update={"mass": 0.050})
    truth = objects.model_copy(update={"containers": {**objects.containers, "vial1": heavy}})
    joints = {name: arm.joint_names for name, arm in compiled.cell.arms.items()}
    q0 = compiled.program.segments[0].trajectory.q[0]
    return SimDriver(compiled.world.cell, joints, objects=truth, q0=q0)
