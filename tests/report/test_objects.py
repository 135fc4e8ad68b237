"""The lab objects the page draws: containers at their ``at`` keypoints, carried by the
gripper that holds them, a vial's cap on it; the cell's zones."""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest

from cellengine.info.load import load_world
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.program import GripperEvent, TimedEvent
from cellengine.report.objects import CAP_SHARE, containers, zones
from cellengine.world import World
from tests.conftest import CELLS

LAB = CELLS / "lab_bench"


@cache
def lab_cell() -> tuple[World, CellModel]:
    world = load_world(LAB / "cell.yaml", LAB / "objects.yaml")
    return world, build_cell_model(world)


def test_containers_stand_at_their_keypoints_and_vials_have_caps() -> None:
    world, cell = lab_cell()
    home = cell.join({name: arm.home for name, arm in cell.arms.items()})
    shapes = {s["name"]: s for s in containers(world, cell, (), np.array([0.0]), home[None])}
    assert len(shapes) == 5 * 2 + 1 + 4  # five vials with their caps, the beaker, four bottles
    vial = shapes["vial1"]
    assert (vial["kind"], vial["object"], vial["fixed"]) == ("cylinder", "vial", True)
    assert vial["radius"] == pytest.approx(0.014, abs=1e-9)
    base = world.pose("bench.rack1.slot1")[:3, 3]
    split = 0.060 * (1 - CAP_SHARE)

    def up(z: float) -> np.ndarray:
        return base + np.array([0.0, 0.0, z])

    assert vial["points"] == pytest.approx([*base, *up(split)], abs=1e-4)
    cap = shapes["vial1 cap"]
    assert cap["object"] == "cap"
    assert cap["points"] == pytest.approx([*up(split), *up(0.06)], abs=1e-4)
    beaker = shapes["beaker"]
    assert (beaker["object"], beaker["radius"]) == ("beaker", pytest.approx(0.035, abs=1e-9))


def test_a_held_container_moves_with_the_gripper_until_let_go() -> None:
    """robot1 lifts its z axis 100 mm over 2 s (linearly); it grasps vial1 at 0 s and lets go
    at 1 s: the vial rises 50 mm and stays there; vial2 never moves."""
    world, cell = lab_cell()
    home = cell.join({name: arm.home for name, arm in cell.arms.items()})
    times = np.linspace(0.0, 2.0, 51)
    q = np.repeat(home[None], len(times), axis=0)
    q[:, cell.joint_names.index("robot1_z")] += 0.1 * times / 2.0
    events = (
        TimedEvent(0.0, GripperEvent("robot1", "grasp", "vial1")),
        TimedEvent(1.0, GripperEvent("robot1", "open", None)),
    )
    shapes = {s["name"]: s for s in containers(world, cell, events, times, q)}
    vial, cap = shapes["vial1"], shapes["vial1 cap"]
    assert not vial["fixed"] and vial["stride"] == 6
    points = np.array(vial["points"]).reshape(len(times), 6)
    base = world.pose("bench.rack1.slot1")[:3, 3]
    rise = points[:, 2] - base[2]
    assert rise[times <= 1.0] == pytest.approx(0.05 * times[times <= 1.0], abs=1e-4)
    assert rise[times >= 1.0] == pytest.approx(0.05, abs=1e-4)
    assert points[:, :2] == pytest.approx(np.repeat(base[None, :2], len(times), 0), abs=1e-4)
    cap_points = np.array(cap["points"]).reshape(len(times), 6)
    assert cap_points[:, 2] == pytest.approx(points[:, 5], abs=1e-4)  # on the vial
    assert shapes["vial2"]["fixed"] and len(shapes["vial2"]["points"]) == 6


def test_zones() -> None:
    world, _ = lab_cell()
    assert zones(world) == [
        {"name": "private1", "min": [0.0, 0.0, 0.0], "max": [1.5, 0.37, 0.4], "robots": ["robot1"]},
        {
            "name": "shared",
            "min": [0.0, 0.37, 0.0],
            "max": [1.5, 0.93, 0.4],
            "robots": ["robot1", "robot2"],
        },
        {"name": "private2", "min": [0.0, 0.93, 0.0], "max": [1.5, 1.3, 0.4], "robots": ["robot2"]},
    ]
