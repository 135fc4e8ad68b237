"""The lab bench (cells/lab_bench/): the cooperative cartesian platform of paper 004 and the same
bench with two UR5e. The files validate; the keypoints are where the layout says; the zones
match what each robot reaches (inverse kinematics with the robot's grasps); and each experiment's
premise holds: what the plans rely on is true of the cell, not just asserted in a comment."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.cli import main
from cellengine.info.cell import SimDriver
from cellengine.info.load import load_plan, load_world
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import ArmIK
from cellengine.motion.robot import CellModel, build_cell_model
from cellengine.motion.scene import CollisionScene, build_scene, rearranged
from cellengine.skill import HeavierOf
from cellengine.skills.lab import Place, Pour, Unscrew, Weigh
from cellengine.world import World
from tests.conftest import CELLS

LAB = CELLS / "lab_bench"
CARTESIAN = LAB / "cell.yaml"
UR = LAB / "cell_ur.yaml"
OBJECTS = LAB / "objects.yaml"
PLANS = ("plan_weigh_handover", "plan_relocate", "plan_pour_heavier", "plan_cluttered")

# Where a grasp holds an object standing at a keypoint: from above 15 mm below its top (a vial's
# cap), from the side 30 mm above its base (a vial's body); a place with nothing on it as if a
# 60 mm vial stood there. The unscrew station's `hold` and `cap` are grasp points themselves.
BELOW_TOP = 0.015
SIDE_HEIGHT = 0.030
VIAL_HEIGHT = 0.060
GRASP_POINTS = ("hold", "cap")
YAWS = [k * math.pi / 4 for k in range(8)]

# Which zone each fixture of the bench is in (bench/models.xml, cell.yaml's comments).
ZONE_OF = {
    "rack1": "private1",
    "free1": "private1",
    "free2": "private1",
    "beaker": "private1",
    "rack2": "private2",
    "free3": "private2",
    "free4": "private2",
    "rack_s1": "shared",
    "rack_s2": "shared",
    "free_s1": "shared",
    "free_s2": "shared",
    "handover": "shared",
    "unscrew": "shared",
    "clutter1": "shared",
    "clutter2": "shared",
}


# ---------------------------------------------------------------------------------- helpers


@cache
def world(cell: Path) -> World:
    return load_world(cell, OBJECTS)


@cache
def model(cell: Path) -> CellModel:
    return build_cell_model(world(cell))


@cache
def solver(cell: Path, robot: str) -> ArmIK:
    # few restarts: on the cartesian robots a pose the axes can reach converges from any seed,
    # and most of the poses asked here are out of reach by construction
    return ArmIK(model(cell).arms[robot], max_restarts=2)


@cache
def scene(cell: Path) -> CollisionScene:
    return build_scene(model(cell), world(cell))


def grasp_poses(p: Any, kind: str) -> Iterator[Any]:
    """TCP poses grasping at point ``p``: from above (z down) turned about the vertical, or from
    the side (z horizontal, the jaw axis y horizontal) from every direction, x down or up."""
    for yaw in YAWS:
        if kind == "top":
            yield g.transform(g.rot_z(yaw) @ g.rot_x(math.pi), p)
        else:
            side = g.rot_z(yaw) @ g.rot_y(math.pi / 2)  # z along (cos yaw, sin yaw, 0), x down
            yield g.transform(side, p)
            yield g.transform(side @ g.rot_z(math.pi), p)  # x up


def grasp_point(w: World, ref: str, kind: str) -> Any:
    p = w.pose(ref)[:3, 3]
    if ref.rsplit(".", 1)[-1] in GRASP_POINTS:
        return p
    standing = [c.height for c in w.objects.containers.values() if c.at == ref]
    height = standing[0] if standing and standing[0] is not None else VIAL_HEIGHT
    up = height - BELOW_TOP if kind == "top" else SIDE_HEIGHT
    return p + np.array([0.0, 0.0, up])


def grasps(cell: Path, robot: str, ref: str, kind: str | None = None) -> list[Any]:
    """The robot's joint positions grasping at keypoint ``ref``, with ``kind`` of grasp (default:
    its tool's), one per reachable grasp pose."""
    w = world(cell)
    tool = w.cell.tools[str(w.cell.robots[robot].tool)]
    kind = kind or tool.grasp
    ik = solver(cell, robot)
    found = (ik.solve(T) for T in grasp_poses(grasp_point(w, ref, kind), kind))
    return [q for q in found if q is not None]


def reaches(cell: Path, robot: str, ref: str) -> bool:
    """Whether the robot reaches keypoint ``ref`` with a top or a side grasp."""
    return any(grasps(cell, robot, ref, kind) for kind in ("top", "side"))


def zone_of(w: World, ref: str) -> str:
    p = w.pose(ref)[:3, 3]
    inside = [name for name, z in w.cell.zones.items() if z.contains(p)]
    assert len(inside) == 1, f"{ref} at {p} is in zones {inside}"
    return inside[0]


def keypoints(cell: Path) -> list[str]:
    return list(world(cell).keypoints())


def home_tcp(cell: Path, robot: str) -> Any:
    arm = model(cell).arms[robot]
    assert arm.home is not None
    return arm.fk(arm.home)[:3, 3]


def with_homes(cell: Path, **qs: Any) -> Any:
    m = model(cell)
    homes: dict[str, Any] = {name: arm.home for name, arm in m.arms.items()}
    return m.join({**homes, **qs})


# ---------------------------------------------------------------------------------- files


def test_every_file_validates(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["validate", "--no-compile", "--format", "json", str(LAB)]) == 0
    report = json.loads(capsys.readouterr().out)
    got = {Path(f["file"]).name: (f["kind"], f["ok"]) for f in report["files"]}
    assert got == {
        "cell.yaml": ("cell", True),
        "cell_ur.yaml": ("cell", True),
        "objects.yaml": ("objects", True),
        **{f"{plan}.yaml": ("plan", True) for plan in PLANS},
    }


@pytest.mark.parametrize("cell", [CARTESIAN, UR], ids=["cartesian", "ur"])
def test_the_plans_load_in_either_cell(cell: Path) -> None:
    for plan in PLANS:
        loaded = load_plan(LAB / f"{plan}.yaml", cell=cell)
        assert loaded.world.cell_file == cell
        assert set(loaded.world.cell.robots) == {"robot1", "robot2"}


def test_both_cells_share_platforms_zones_and_driver() -> None:
    cart, ur = world(CARTESIAN).cell, world(UR).cell
    assert cart.platforms == ur.platforms
    assert cart.zones == ur.zones
    assert cart.obstacles == ur.obstacles
    assert cart.driver == ur.driver
    for name in ("robot1", "robot2"):
        a, b = cart.tools[str(cart.robots[name].tool)], ur.tools[str(ur.robots[name].tool)]
        assert (a.grasp, a.load_cell, a.jaw) == (b.grasp, b.load_cell, b.jaw)
    assert isinstance(ur.robots["robot1"].model, str)  # a built-in UR5e


def test_keypoints_are_where_the_layout_says() -> None:
    kp = {n: T for n, T in world(CARTESIAN).keypoints().items()}
    expected_mm = {
        "bench.rack1.slot1": (300, 150, 6),
        "bench.rack1.slot3": (300, 270, 6),
        "bench.rack_s1.slot1": (400, 450, 6),
        "bench.rack_s2.slot3": (400, 850, 6),
        "bench.rack2.slot2": (300, 1090, 6),
        "bench.free1.place": (550, 210, 2),
        "bench.free4.place": (950, 1090, 2),
        "bench.free_s1.place": (1000, 450, 2),
        "bench.beaker.place": (1100, 210, 2),
        "bench.handover.place": (750, 650, 6),
        "bench.unscrew.hold": (950, 650, 81),
        "bench.unscrew.cap": (950, 650, 108.5),
        "bench.clutter1.target": (1150, 560, 2),
        "bench.clutter1.blocker": (1114, 560, 2),
        "bench.clutter2.blocker": (1114, 740, 2),
    }
    for name, xyz in expected_mm.items():
        # (Blender writes the root's axis as 0.707107: a few 1e-5 mm off)
        assert kp[name][:3, 3] * 1000 == pytest.approx(xyz, abs=1e-3), name
    # every keypoint z up, the bench's axes along the cell's (the Blender root turned back)
    for name, T in kp.items():
        assert T[:3, :3] == pytest.approx(np.eye(3), abs=1e-6), name
    assert len(kp) == 27


def test_containers_stand_at_their_keypoints() -> None:
    w = world(CARTESIAN)
    at = {name: c.at for name, c in w.objects.containers.items()}
    assert at["vial3"] == "bench.rack2.slot2"
    assert at["beaker"] == "bench.beaker.place"
    for name, c in w.objects.containers.items():
        assert c.at is not None and c.height is not None and c.mass is not None, name
        if c.kind == "vial":
            assert c.cap is not None and c.diameter is not None
            assert c.cap.pitch == pytest.approx(0.002) and c.cap.turns == 2.5
            # the jaw modes fit these vials: open clears them, grasp squeezes them
            for tool in w.cell.tools.values():
                assert tool.jaw["open"] > c.diameter > tool.jaw["grasp"]
    # two objects never stand at one place
    assert len(set(at.values())) == len(at)


# ---------------------------------------------------------------------------------- robots


@pytest.mark.parametrize("cell", [CARTESIAN, UR], ids=["cartesian", "ur"])
def test_robot_models_build(cell: Path) -> None:
    m = model(cell)
    assert list(m.arms) == ["robot1", "robot2"]
    if cell == CARTESIAN:
        assert m.joint_names == (
            "robot1_z",
            "robot1_x",
            "robot1_y",
            "robot1_roll",
            "robot2_z",
            "robot2_x",
            "robot2_y",
            "robot2_turn",
        )
    else:
        assert m.nq == 12 and m.joint_names[0] == "robot1_shoulder_pan_joint"
    assert all(arm.home is not None for arm in m.arms.values())


def test_cartesian_robots_are_the_published_ones() -> None:
    """Z first, then X, then Y at the end, the Y axes extending towards each other; robot1's
    last joint turns about x, robot2's about z; 1.5 m x 0.93 m of travel; the lead-screw Z
    slower than the belts."""
    m = model(CARTESIAN)
    towards_other = {"robot1": 1.0, "robot2": -1.0}  # robot1 at y = 0, robot2 at y = 1300 mm
    last_axis = {"robot1": (1.0, 0.0, 0.0), "robot2": (0.0, 0.0, 1.0)}
    for name, arm in m.arms.items():
        assert arm.home is not None
        J = arm.jacobian(arm.home)
        assert J[:3, 0] == pytest.approx((0, 0, 1), abs=1e-9)  # Z lifts everything after it
        assert J[:3, 1] == pytest.approx((1, 0, 0), abs=1e-9)
        assert J[:3, 2] == pytest.approx((0, towards_other[name], 0), abs=1e-9)
        assert np.abs(J[3:, :3]).max() == 0  # three linear axes
        assert J[3:, 3] == pytest.approx(last_axis[name], abs=1e-9)
        lim = arm.limits
        assert (lim.upper - lim.lower)[:3] == pytest.approx((0.30, 1.5, 0.93))
        assert lim.velocity[0] < min(lim.velocity[1], lim.velocity[2]) <= 0.5
        # retracted at home (the paper's start-up): the Y arm out of the shared zone
        assert arm.home[2] == 0
        assert not world(CARTESIAN).cell.zones["shared"].contains(arm.fk(arm.home)[:3, 3])
    # robot1 turns one full turn; robot2's cap-turning joint takes a 2.5-turn cap in one go
    assert m.arms["robot1"].limits.upper[3] == pytest.approx(math.pi)
    assert m.arms["robot2"].limits.upper[3] - m.arms["robot2"].limits.lower[3] > 2.5 * math.tau


def test_tools_are_the_published_grippers() -> None:
    cell = world(CARTESIAN).cell
    tools = {name: cell.tools[str(robot.tool)] for name, robot in cell.robots.items()}
    assert (tools["robot1"].grasp, tools["robot1"].load_cell) == ("side", True)
    assert (tools["robot2"].grasp, tools["robot2"].load_cell) == ("top", False)
    # where each gripper's fingers point at home: robot1's along +x, robot2's down
    approach = {r: arm.fk(np.asarray(arm.home))[:3, 2] for r, arm in model(CARTESIAN).arms.items()}
    assert approach["robot1"] == pytest.approx((1, 0, 0), abs=1e-9)
    assert approach["robot2"] == pytest.approx((0, 0, -1), abs=1e-9)


@pytest.mark.parametrize("cell", [CARTESIAN, UR], ids=["cartesian", "ur"])
def test_homes_are_free(cell: Path) -> None:
    checker = CollisionChecker(scene(cell))
    q = with_homes(cell)
    assert checker.check(q) is None
    distance, pair = checker.distance(q, between=("robot1", "robot2"))
    assert distance > 0.5, pair  # the arms start far apart, each over its own strip


def test_cartesian_links_never_meet_themselves() -> None:
    """The URDFs' boxes are sized so that no two links of one robot that a joint does not join
    ever come within the sampling margin: no self pair is left to check."""
    checked = scene(CARTESIAN).checked
    own = [(a, b) for a, b in checked if a.split("/")[0] == b.split("/")[0]]
    assert own == []


@pytest.mark.parametrize("cell", [CARTESIAN, UR], ids=["cartesian", "ur"])
def test_every_place_can_be_worked_at(cell: Path) -> None:
    """Every place (all but the cluttered targets, blocked on purpose, and the unscrew
    station's grasp points, tested with both arms below) can be grasped at by each robot that
    may work in its zone without touching anything but what stands there: nothing stands in
    the way of robot1's side gripper, which comes in along +x on the cartesian cell."""
    w = world(cell)
    full = scene(cell)
    for ref in keypoints(cell):
        name = ref.rsplit(".", 1)[-1]
        if name in (*GRASP_POINTS, "target"):
            continue
        standing = [n for n, c in w.objects.containers.items() if c.at == ref]
        statics = [s for s in full.statics if s.name not in standing]
        checker = CollisionChecker(rearranged(full, statics, {}, {}))
        for robot in w.cell.zones[zone_of(w, ref)].robots:
            free = [
                q
                for q in grasps(cell, robot, ref)
                if checker.check(with_homes(cell, **{robot: q})) is None
            ]
            assert free, f"{robot} cannot work at {ref}"


# ---------------------------------------------------------------------------------- zones


def test_zones_tile_the_bench() -> None:
    zones = world(CARTESIAN).cell.zones
    assert set(zones) == {"private1", "shared", "private2"}
    assert zones["private1"].robots == ("robot1",)
    assert zones["private2"].robots == ("robot2",)
    assert set(zones["shared"].robots) == {"robot1", "robot2"}
    # private1 | shared | private2 along y, edge to edge
    assert zones["private1"].max[1] == pytest.approx(zones["shared"].min[1])
    assert zones["shared"].max[1] == pytest.approx(zones["private2"].min[1])
    # y_s > y_r: each robot's reach (930 mm) is less than their distance (1300 mm)
    reach = zones["shared"].max[1] - zones["private1"].min[1]
    separation = zones["private2"].max[1] - zones["private1"].min[1]
    assert separation > reach > separation / 2
    assert zones["shared"].handovers == ("bench.handover",)
    assert zones["shared"].cooperation == ("bench.unscrew",)
    # each zone's free places are free_place elements inside it, and no object stands there
    w = world(CARTESIAN)
    taken = {c.at for c in w.objects.containers.values()}
    for name, zone in zones.items():
        assert len(zone.free) == 2, name
        for ref in zone.free:
            assert w.element(ref).model == "free_place"
            assert zone_of(w, ref) == name and f"{ref}.place" not in taken


@pytest.mark.parametrize("ref", keypoints(CARTESIAN))
def test_each_keypoint_is_in_its_zone(ref: str) -> None:
    element = ref.split(".")[1]
    assert zone_of(world(CARTESIAN), ref) == ZONE_OF[element]


@pytest.mark.parametrize("ref", keypoints(CARTESIAN))
def test_cartesian_reach_matches_the_zones(ref: str) -> None:
    """Who reaches a keypoint with a top or side grasp is who may work in its zone: private
    keypoints only their robot, shared ones both."""
    w = world(CARTESIAN)
    zone = w.cell.zones[zone_of(w, ref)]
    got = {robot for robot in w.cell.robots if reaches(CARTESIAN, robot, ref)}
    assert got == set(zone.robots)


@pytest.mark.parametrize("ref", keypoints(CARTESIAN))
def test_cartesian_robots_grasp_only_their_way(ref: str) -> None:
    """robot1 grasps only from the side (its gripper cannot point down), robot2 only from
    above (it cannot tilt its gripper)."""
    for robot, other in (("robot1", "top"), ("robot2", "side")):
        assert grasps(CARTESIAN, robot, ref, other) == []


@pytest.mark.parametrize("ref", keypoints(UR))
def test_ur_arms_reach_their_zones(ref: str) -> None:
    """Each UR5e reaches, with its own gripper's grasp, every keypoint of the zones it may work
    in (it reaches more: there the zones, not the reach, keep it out)."""
    w = world(UR)
    for robot in w.cell.zones[zone_of(w, ref)].robots:
        assert grasps(UR, robot, ref), f"{robot} cannot grasp at {ref}"


# ---------------------------------------------------------------------------------- premises


def test_experiment_1_needs_a_handover() -> None:
    """Weigh an object only robot2 can reach; only robot1's tool weighs."""
    (step,) = load_plan(LAB / "plan_weigh_handover.yaml").plan.steps
    assert isinstance(step, Weigh) and isinstance(step.object, str)
    assert step.arm == "auto"
    w = world(CARTESIAN)
    at = w.objects.containers[step.object].at
    assert at is not None
    weighers = {r for r, robot in w.cell.robots.items() if w.cell.tools[str(robot.tool)].load_cell}
    assert weighers == {"robot1"}
    assert not reaches(CARTESIAN, "robot1", at)
    assert grasps(CARTESIAN, "robot2", at)
    assert zone_of(w, at) == "private2"  # on the UR cell too: the same zones
    # the handover place, where robot2 puts it down and robot1 picks it up
    (handover,) = w.cell.zones["shared"].handovers
    for cell in (CARTESIAN, UR):
        assert grasps(cell, "robot1", handover) and grasps(cell, "robot2", handover)


@pytest.mark.parametrize("cell", [CARTESIAN, UR], ids=["cartesian", "ur"])
def test_experiment_2_each_vial_is_nearer_a_different_robot(cell: Path) -> None:
    steps = load_plan(LAB / "plan_relocate.yaml").plan.steps
    assert all(not s.after and s.arm == "auto" for s in steps)
    w = world(cell)
    nearer = []
    for step in steps:
        assert isinstance(step, Place) and isinstance(step.object, str)
        at = w.objects.containers[step.object].at
        assert at is not None
        for ref in (at, step.to):
            assert zone_of(w, ref) == "shared"
            assert grasps(cell, "robot1", ref) and grasps(cell, "robot2", ref), ref
        p = w.pose(at)[:3, 3]
        d = {r: float(np.linalg.norm(home_tcp(cell, r) - p)) for r in ("robot1", "robot2")}
        nearer.append(min(d, key=d.__getitem__))
        assert abs(d["robot1"] - d["robot2"]) > 0.05  # not a close call
    assert nearer == ["robot1", "robot2"]
    # and with the robots' paths summed, one robot doing both costs more: from where it puts one
    # vial down, the other vial is further than that vial's own robot is at home
    for step, other, robot in ((steps[0], steps[1], "robot1"), (steps[1], steps[0], "robot2")):
        assert isinstance(step, Place) and isinstance(other, Place)
        at = w.objects.containers[str(step.object)].at
        assert at is not None
        p = w.pose(at)[:3, 3]
        from_home = float(np.linalg.norm(home_tcp(cell, robot) - p))
        from_other = float(np.linalg.norm(w.pose(other.to)[:3, 3] - p))
        assert from_other > from_home + 0.05


def test_experiment_3_precedence_and_the_heavier_vial() -> None:
    steps = {s.id: s for s in load_plan(LAB / "plan_pour_heavier.yaml").plan.steps}
    assert list(steps) == ["weigh1", "weigh2", "unscrew", "pour"]
    weighs = [steps["weigh1"], steps["weigh2"]]
    unscrew, pour = steps["unscrew"], steps["pour"]
    assert isinstance(unscrew, Unscrew) and isinstance(pour, Pour)
    assert all(isinstance(s, Weigh) and s.after == () for s in weighs)
    assert set(unscrew.after) == {"weigh1", "weigh2"}
    assert pour.after == ("unscrew",)
    choice = unscrew.object
    assert isinstance(choice, HeavierOf) and pour.object == choice
    named = list(choice.heavier_of)
    assert named == [getattr(s, "object", None) for s in weighs]  # what was weighed
    w = world(CARTESIAN)
    masses = {n: w.objects.containers[n].mass or 0.0 for n in named}
    assert max(masses, key=masses.__getitem__) == named[1] == "vial2"
    driver = w.cell.driver
    assert isinstance(driver, SimDriver)
    assert masses["vial2"] - masses["vial1"] > 20 * driver.mass_noise > 0
    # robot1 (the load cell) reaches both vials, and the beaker: only it can pour (tilt)
    for name in named:
        at = w.objects.containers[name].at
        assert at is not None and grasps(CARTESIAN, "robot1", at)
    assert pour.into == "beaker"
    assert grasps(CARTESIAN, "robot1", "bench.beaker.place")
    assert not reaches(CARTESIAN, "robot2", "bench.beaker.place")


@pytest.mark.parametrize("cell", [CARTESIAN, UR], ids=["cartesian", "ur"])
def test_experiment_3_the_arms_meet_at_the_unscrew_station(cell: Path) -> None:
    """robot1 holds the vial from the side at `hold` while robot2 grips the cap from above at
    `cap`, both arms free and clear of each other. On the cartesian cell robot1 has one approach
    (+x, with its jaw either way up), and every grasp of it is clear of every turn of robot2's
    gripper; on the UR cell some pair of grasps (robot2's IK branch nearest home) is."""
    (station,) = world(cell).cell.zones["shared"].cooperation
    hold, cap = grasps(cell, "robot1", f"{station}.hold"), grasps(cell, "robot2", f"{station}.cap")
    assert hold and len(cap) == len(YAWS)
    checker = CollisionChecker(scene(cell))

    def clear(q1: Any, q2: Any) -> bool:
        q = with_homes(cell, robot1=q1, robot2=q2)
        return checker.check(q) is None and checker.distance(q, ("robot1", "robot2"))[0] > 0.005

    if cell == CARTESIAN:
        assert len(hold) == 2
        assert all(clear(q1, q2) for q1 in hold for q2 in cap)
    else:
        assert any(clear(q1, q2) for q1 in hold for q2 in cap)


def test_cluttered_targets_are_blocked_for_both_robots() -> None:
    """Every grasp either robot has of a target hits that target's blocker, and is free once
    the blocker is gone; the blockers themselves can be taken by either robot."""
    cell = CARTESIAN
    full = scene(cell)
    steps = load_plan(LAB / "plan_cluttered.yaml").plan.steps
    assert all(isinstance(s, Place) for s in steps)
    targets = [getattr(s, "object", None) for s in steps]
    assert targets == ["target1", "target2"]
    # each target goes to a different robot's private zone: one target per arm
    assert [zone_of(world(cell), getattr(s, "to", "")) for s in steps] == ["private1", "private2"]

    def without(*names: str) -> CollisionChecker:
        statics = [s for s in full.statics if s.name not in names]
        return CollisionChecker(rearranged(full, statics, {}, {}))

    for k, target in enumerate(targets, start=1):
        blocker = f"blocker{k}"
        spot = f"bench.clutter{k}"
        assert world(cell).objects.containers[target].at == f"{spot}.target"
        assert world(cell).objects.containers[blocker].at == f"{spot}.blocker"
        blocked, cleared = without(target), without(target, blocker)
        for robot in ("robot1", "robot2"):
            qs = grasps(cell, robot, f"{spot}.target")
            assert qs, f"{robot} cannot reach {target}"
            for q in qs:
                hit = blocked.check(with_homes(cell, **{robot: q}))
                assert hit is not None and blocker in hit.pair, (robot, target, hit)
                assert cleared.check(with_homes(cell, **{robot: q})) is None
            free = without(blocker)
            for q in grasps(cell, robot, f"{spot}.blocker"):
                assert free.check(with_homes(cell, **{robot: q})) is None
            assert grasps(cell, robot, f"{spot}.blocker")
