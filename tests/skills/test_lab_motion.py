"""The lab motion primitives on the reference cable cell's two UR5e, with vials standing at
keypoints both arms reach: grasps, state hand-over, unscrew strokes, pour, weigh facts."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.errors import InputError
from cellengine.info.load import load_world
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import build_cell_model, is_tool
from cellengine.skills import lab_geometry as lg
from cellengine.skills import lab_motion as lm
from cellengine.skills.lab_state import LabState
from cellengine.world import World
from tests.conftest import CELLS

OBJECTS = """
containers:
  vial1: {kind: vial, diameter: 28, height: 60, mass: 30, at: holder.comb_b.slot,
          cap: {kind: screw, pitch: 2, turns: 2.5}}
  beaker: {kind: beaker, diameter: 60, height: 80, at: routing.guide2.slot}
"""


@pytest.fixture(scope="module")
def world(tmp_path_factory: pytest.TempPathFactory) -> World:
    folder = tmp_path_factory.mktemp("lab") / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    objects = folder / "objects.yaml"
    objects.write_text(objects.read_text() + OBJECTS)
    return load_world(folder / "cell.yaml", objects)


@pytest.fixture(scope="module")
def reach(world: World) -> lm.Solver:
    model = build_cell_model(world)
    iks = {name: arm_ik(arm) for name, arm in model.arms.items()}
    return lambda arm, T, ignore=(): iks[arm].solve(T) is not None


def _start(world: World) -> LabState:
    model = build_cell_model(world)
    tcp = {name: arm.fk(arm.home) for name, arm in model.arms.items() if arm.home is not None}
    return LabState.start(world, tcp)


def test_top_pick_grasps_the_cap_from_above_and_lifts(world: World, reach: lm.Solver) -> None:
    b = lm.Builder(_start(world))
    lm.pick(b, reach, world, "right", "vial1", "top", "steps[0] Pick vial1")
    labels = [s.label for s in b.segments]
    assert labels == [
        "steps[0] Pick vial1: to vial1",
        "steps[0] Pick vial1: grasp vial1",
        "steps[0] Pick vial1: lift vial1",
    ]
    grasp = b.segments[1].paths[0].poses[-1]
    base = world.pose("holder.comb_b.slot")[:3, 3]
    # on the axis, round the cap (15 mm high: its middle 7.5 mm below the 60 mm top)
    assert np.allclose(grasp[:3, 3], base + np.array([0, 0, 0.0525]), atol=1e-9)
    assert np.allclose(grasp[:3, 2], [0, 0, -1])
    assert reach("right", grasp)
    assert b.segments[1].after[0].holds == "vial1"
    assert b.state.holder("vial1") == "right" and "vial1" not in b.state.where
    lifted = b.segments[2].paths[0].poses[-1]
    assert lifted[2, 3] - grasp[2, 3] == pytest.approx(lg.LIFT)


def test_place_puts_the_container_where_asked_and_lets_go(world: World, reach: lm.Solver) -> None:
    b = lm.Builder(_start(world))
    lm.pick(b, reach, world, "right", "vial1", "top", "w")
    target = world.pose("holder.comb_a.slot")
    lm.place(b, reach, "right", target, "w")
    assert "right" not in b.state.held
    assert np.allclose(b.state.where["vial1"][:3, 3], target[:3, 3], atol=1e-9)
    put = next(s for s in b.segments if s.label == "w: put down vial1")
    assert put.after[0].mode == "open" and put.after[0].holds is None


def test_side_grasps_come_in_horizontally_away_from_the_base_first(world: World) -> None:
    body = lg.Body.of(world.container("vial1"))
    T_at = world.pose("holder.comb_b.slot")
    base = np.array([0.0, -0.35, 0.0])
    first, *rest = lg.grasp_candidates("side", T_at, body, base)
    away = lg.horizontal(T_at[:3, 3] - base)
    # the 15 deg heading nearest the direction away from the base
    assert math.degrees(math.acos(float(first[:3, 2] @ away))) <= 7.5
    heading = math.degrees(math.atan2(first[1, 2], first[0, 2]))
    assert heading / 15 == pytest.approx(round(heading / 15), abs=1e-9)
    assert abs(first[2, 2]) < 1e-9 and abs(first[2, 1]) < 1e-9  # z and jaw horizontal
    assert first[2, 3] == pytest.approx(T_at[2, 3] + (0.06 - 0.015) * 2 / 3)  # body, 2/3 up
    assert len(rest) == 2 * len(lg.SIDE_HEADINGS_DEG) - 1  # each heading both ways round


def test_unscrew_turns_two_and_a_half_turns_in_half_turn_strokes(
    world: World, reach: lm.Solver
) -> None:
    assert lm.unscrew_strokes(2.5) == pytest.approx([math.pi] * 5)
    b = lm.Builder(_start(world))
    cap_place = world.pose("holder.comb_a.slot")
    lm.unscrew(b, reach, world, "right", "vial1", "steps[2] Unscrew vial1")
    lm.put_cap_down(b, reach, world, "right", "vial1", cap_place, "steps[2] Unscrew vial1")
    turns = [s for s in b.segments if "turn the cap" in s.label]
    assert len(turns) == 5
    first = turns[0].paths[0].poses
    # rises by the pitch per turn: half a turn, 1 mm
    assert first[-1][2, 3] - first[0][2, 3] == pytest.approx(0.001)
    # turned +180 deg about the vertical (counter-clockwise from above)
    R = first[-1][:3, :3] @ first[0][:3, :3].T
    assert math.atan2(R[1, 0], R[0, 0]) == pytest.approx(math.pi, abs=1e-9)
    assert turns[-1].before[0].holds == "vial1.cap" and not turns[-1].after
    assert all(t.after[0].mode == "open" for t in turns[:-1])
    assert "vial1" not in b.state.capped and "vial1" in b.state.caps
    with pytest.raises(InputError, match="'vial1' has no cap on to unscrew"):
        lm.unscrew(b, reach, world, "right", "vial1", "again")


def test_unscrew_turns_as_many_turns_as_the_step_gives(world: World, reach: lm.Solver) -> None:
    b = lm.Builder(_start(world))
    lm.unscrew(b, reach, world, "right", "vial1", "steps[2] Unscrew vial1", turns=3.0)
    turns = [s for s in b.segments if "turn the cap" in s.label]
    assert len(turns) == 6  # half-turn strokes
    rise = sum(t.paths[0].poses[-1][2, 3] - t.paths[0].poses[0][2, 3] for t in turns)
    assert rise == pytest.approx(0.006)  # 3 turns of a 2 mm pitch


def test_pour_is_refused_while_capped_then_tilts_over_the_target(
    world: World, reach: lm.Solver
) -> None:
    b = lm.Builder(_start(world))
    lm.pick(b, reach, world, "right", "vial1", "top", "p")
    with pytest.raises(InputError) as e:
        lm.pour(b, reach, world, "right", "vial1", "beaker", math.radians(100), "steps[3] Pour")
    assert e.value.problems[0].message == (
        "steps[3] Pour: 'vial1' is capped: unscrew it before pouring"
    )
    b.state = b.state.uncapped("vial1", world.pose("holder.comb_a.slot"))
    lm.pour(b, reach, world, "right", "vial1", "beaker", math.radians(100), "steps[3] Pour")
    over, tilt, back = b.segments[-3:]
    assert over.paths[0].kind == "transit"
    poses = tilt.paths[0].poses
    T0, T1 = poses[0], poses[-1]
    angle = math.acos((np.trace(T1[:3, :3] @ T0[:3, :3].T) - 1) / 2)
    assert angle == pytest.approx(math.radians(100))
    held = b.state.held["right"]
    beaker = world.pose("routing.guide2.slot")[:3, 3]
    rim = beaker[2] + 0.08 + lm.POUR_CLEARANCE
    # tilted, the vial's mouth is over the beaker's axis
    mouth = (T1 @ np.linalg.inv(held.T_base_tcp) @ g.transform(None, [0, 0, 0.06]))[:3, 3]
    assert np.allclose(mouth[:2], beaker[:2], atol=1e-9)
    # and at no tilt does any point of the vial's axis come below the rim
    for T in poses:
        T_base = T @ np.linalg.inv(held.T_base_tcp)
        for z in np.linspace(0.0, 0.06, 7):
            assert (T_base @ g.transform(None, [0, 0, z]))[2, 3] > rim
    assert np.allclose(back.paths[0].poses[-1], T0)


def test_weigh_tells_the_runner_what_to_read(world: World, reach: lm.Solver) -> None:
    b = lm.Builder(_start(world))
    with pytest.raises(InputError, match="arm 'left' must hold 'vial1' to weigh it"):
        lm.weigh(b, "left", "vial1", "w")
    lm.pick(b, reach, world, "right", "vial1", "top", "w")
    lm.weigh(b, "right", "vial1", "w")
    assert dict(b.segments[-1].facts) == {"measure": "mass", "object": "vial1", "arm": "right"}


@pytest.mark.parametrize("grasp", ["top", "side"])
def test_a_vial_weighed_again_and_again_stands_as_it_stood(
    world: World, reach: lm.Solver, grasp: lg.Grasp
) -> None:
    """Issue 19: each set-down composed the grasp with its inverse (a transpose), which
    tripled the round-off off a rotation each time: after ~30 weighings the vial leant and
    slid until it could not be set down."""
    b = lm.Builder(_start(world))
    T0 = b.state.where["vial1"]
    for _ in range(12):
        lm.pick(b, reach, world, "right", "vial1", grasp, "w")
        lm.weigh(b, "right", "vial1", "w")
        lm.place(b, reach, "right", T0, "w")
    T = b.state.where["vial1"]
    assert g.rotation_angle(T0, T) < 1e-9
    assert np.allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
    assert np.allclose(T[:3, 3], T0[:3, 3], atol=1e-12)


def test_an_unreachable_grasp_is_refused_in_plan_terms(world: World) -> None:
    b = lm.Builder(_start(world))
    with pytest.raises(InputError) as e:
        lm.pick(
            b, lambda arm, T, ignore=(): False, world, "left", "vial1", "top", "steps[1] Pick vial1"
        )
    assert e.value.problems[0].message == (
        "steps[1] Pick vial1: arm 'left' cannot grasp 'vial1': none of 8 grasps round "
        "(200.0, -20.0, 117.5) mm has an inverse kinematics solution (with its approach and "
        "lift) within the joint limits and free of collisions"
    )


def test_paths_are_finite_and_start_where_the_arm_is(world: World, reach: lm.Solver) -> None:
    b = lm.Builder(_start(world))
    lm.pick(b, reach, world, "right", "vial1", "top", "w")
    lm.place(b, reach, "right", world.pose("holder.comb_a.slot"), "w")
    tcp = _start(world).tcp["right"]
    for seg in b.segments:
        for path in seg.paths:
            assert np.isfinite(path.poses).all()
            if path.kind == "cartesian":
                assert np.allclose(path.poses[0][:3, 3], tcp[:3, 3], atol=1e-9)
            tcp = path.poses[-1]


def test_pick_and_place_compile_with_the_vial_in_the_scene(world: World, reach: lm.Solver) -> None:
    """Through the real executor: the standing vial is a collision object (the tool may touch
    it only while grasping it or backing off it), it rides on the gripper at the grasp's
    offset, and stands where it was put down afterwards."""
    from cellengine.execute import Compiler
    from cellengine.motion.collision import CollisionChecker
    from cellengine.motion.scene import build_scene

    model = build_cell_model(world)
    checker = CollisionChecker(build_scene(model, world))
    assert "vial1" in checker.scene.names and "beaker" in checker.scene.names
    state = _start(world)
    b = lm.Builder(state)
    lm.pick(b, reach, world, "right", "vial1", "top", "w")
    target = world.pose("holder.comb_a.slot")
    lm.place(b, reach, "right", target, "w")
    q0 = np.concatenate([a.home for a in model.arms.values() if a.home is not None])
    c = Compiler(world, model, checker, q0, "split")
    program = c.add_all(b.segments)
    assert len(program.segments) == len(b.segments)
    held = c.holding.state
    assert not held.by_arm and not held.grips
    stood = np.array(held.standing["vial1"])
    assert np.allclose(stood[:3, 3], target[:3, 3], atol=1e-6)
    # the checker has it there now: its cylinder's centre half its height above the place
    (shape,) = [s for s in c.checker.scene.statics if s.name == "vial1"]
    assert np.allclose(shape.T_cell_shape[:3, 3], target[:3, 3] + np.array([0, 0, 0.03]))


def test_the_vial_blocks_a_tool_that_does_not_grasp_it(world: World, reach: lm.Solver) -> None:
    """At the grasp the closed fingers reach into the vial's cylinder: allowed only as a
    contact."""
    from cellengine.execute import Compiler
    from cellengine.execute.held import Holding
    from cellengine.motion.collision import CollisionChecker
    from cellengine.motion.scene import build_scene

    model = build_cell_model(world)
    scene = build_scene(model, world)
    b = lm.Builder(_start(world))
    lm.pick(b, reach, world, "right", "vial1", "top", "w")
    q0 = np.concatenate([a.home for a in model.arms.values() if a.home is not None])
    c = Compiler(world, model, CollisionChecker(scene), q0, "split")
    program = c.add_all(b.segments[:2])  # up to the grasp
    q = np.asarray(program.segments[-1].trajectory.q[-1])
    holding = Holding(world, scene)
    assert holding.checker.check(q) is None  # the open fingers straddle the vial
    holding.set("right", None, mode="grasp")  # closed on it, they are inside its cylinder
    contact = holding.checker.check(q)
    assert contact is not None and "vial1" in contact.pair
    assert any(is_tool(name, "right") for name in contact.pair)
    holding.touch([("right", "vial1")])
    assert holding.checker.check(q) is None
    holding.touch(())
    assert holding.checker.check(q) is not None


def test_two_arms_carry_a_box_as_one_closed_chain(tmp_path: Path) -> None:
    """BimanualCarry: each hand at the middle of the side facing its base, the follower's pose
    relative to the leader's the same at every waypoint of lift, carry and set down, and the
    program (through the executor) leaves the box where it was asked to go."""
    from cellengine.context import build_context
    from cellengine.execute import Compiler
    from cellengine.motion.collision import CollisionChecker
    from cellengine.motion.scene import build_scene
    from cellengine.skills.lab_plan import _Reach

    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    objects = folder / "objects.yaml"
    tray = "  tray: {kind: box, size: [60, 100, 80], mass: 200, at: routing.guide1.slot}\n"
    objects.write_text(objects.read_text() + "containers:\n" + tray)
    # the tray stands among the guides: a hand at its side comes within 10 mm of guide3
    cell_yaml = folder / "cell.yaml"
    cell_yaml.write_text(cell_yaml.read_text() + "clearance: 5\n")
    world = load_world(folder / "cell.yaml", objects)
    ctx = build_context(world)
    model = ctx.cell
    b = lm.Builder(_start(world))
    reach = _Reach(ctx, lambda: b.state.where)
    target = world.pose("routing.guide5.slot")
    lm.carry_together(b, reach, world, "left", "right", "tray", target, "carry")
    chained = [s for s in b.segments if s.closed_chain is not None]
    assert [s.label for s in chained] == [
        "carry: lift tray together",
        "carry: carry tray together",
        "carry: set down tray together",
    ]
    take = next(s for s in b.segments if s.label == "carry: take tray")
    lead0, follow0 = (p.poses[-1] for p in take.paths)
    centre = world.pose("routing.guide1.slot")[:3, 3] + np.array([0, 0, 0.04])
    # guide1's slot turns the box's x (60 mm) along the cell's y, the line between the bases:
    # the hands face each other across those 60 mm, the left (its base at +y) from +y
    assert np.allclose(lead0[:3, 3], centre + np.array([0, 0.03, 0]), atol=1e-6)
    assert np.allclose(follow0[:3, 3], centre - np.array([0, 0.03, 0]), atol=1e-6)
    assert np.allclose(lead0[:3, 2], [0, -1, 0], atol=1e-6)
    T_rel = np.linalg.inv(lead0) @ follow0
    for s in chained:
        lead, follow = s.paths
        assert (lead.arm, follow.arm) == ("left", "right")
        for A, B in zip(lead.poses, follow.poses, strict=True):
            assert np.allclose(np.linalg.inv(A) @ B, T_rel, atol=1e-9)
    model_q0 = np.concatenate([a.home for a in model.arms.values() if a.home is not None])
    c = Compiler(world, model, CollisionChecker(build_scene(model, world)), model_q0, "split")
    c.add_all(b.segments)
    stood = np.array(c.holding.state.standing["tray"])
    assert np.allclose(stood[:3, 3], target[:3, 3], atol=1e-5)
    assert not c.holding.state.by_arm
