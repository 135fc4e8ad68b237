"""The clearance of compiled segments: measured as coal measures it, contacts left out,
refused under the cell's, in report.json."""

from __future__ import annotations

from functools import cache

import numpy as np
import pinocchio as pin
import pytest

from cellengine.errors import StepError
from cellengine.execute.compile import Compiler
from cellengine.motion.clearance import KINDS, ClearanceModel, measured_pairs
from cellengine.motion.scene import attach, held_box, pair_key, rearranged
from cellengine.program import ArmPath, CompiledSegment, Segment
from cellengine.report.data import report_data
from tests.execute.scenes import LEFT_READY, cable_cell, home, line, ready, states


def left_line() -> Segment:
    lx, ly, lz = LEFT_READY
    return Segment(
        1, "left line", (ArmPath("left", "cartesian", line(LEFT_READY, (lx + 0.1, ly, lz))),)
    )


@cache
def compiled() -> tuple[CompiledSegment, CompiledSegment]:
    """ready, then the left arm's line, with no clearance enforced."""
    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell), clearance=0.0)
    first = c.add(ready())
    return first, c.add(left_line())


def brute_force(kind: str, Q: np.ndarray) -> tuple[float, int]:
    """coal's least distance over the measured pairs of ``kind`` at every state, and where."""
    _, cell, checker = cable_cell()
    pairs = ClearanceModel(checker.scene).kinds[kind]  # type: ignore[index]
    data, gdata = cell.model.createData(), pin.GeometryData(pairs.geometry)
    d = [
        float(gdata.distanceResults[k].min_distance)
        for q in Q
        for k in [int(pin.computeDistances(cell.model, data, pairs.geometry, gdata, q))]
    ]
    return min(d), int(np.argmin(d))


@pytest.mark.parametrize("kind", KINDS)
def test_measured_clearance_is_coals_least_distance_at_1ms(kind: str) -> None:
    seg = compiled()[1]
    figure = seg.report["clearance"][kind]
    Q = states(seg.trajectory)
    least, _ = brute_force(kind, Q)
    assert figure["distance_m"] == pytest.approx(least, abs=1e-6)
    # at its time (ties: the distance may stay the least a while), coal says the same
    i = round((figure["time_s"] - seg.trajectory.start_time) / 0.001)
    assert brute_force(kind, Q[i : i + 1])[0] == pytest.approx(figure["distance_m"], abs=1e-9)
    assert 0.0 < figure["distance_m"] < 1.0


def test_arms_figure_names_one_object_of_each_arm() -> None:
    arms = compiled()[1].report["clearance"]["arms"]
    a, b = arms["pair"]
    assert a.startswith("left/") and b.startswith("right/")
    env = compiled()[1].report["clearance"]["environment"]
    assert env["pair"][0].split("/")[0] in ("left", "right") and "/" not in env["pair"][1]


def test_contacts_held_objects_and_fixed_pairs_are_not_measured() -> None:
    checker = cable_cell()[2]
    scene = attach(checker.scene, held_box("box@left", "left", (0.01,) * 3, np.eye(4)))
    scene = rearranged(
        scene, scene.statics, scene.held, {pair_key("right/tool", "routing.guide2"): "contact"}
    )
    names = {
        pair_key(scene.objects[i].name, scene.objects[j].name) for i, j in measured_pairs(scene)[0]
    }
    assert pair_key("right/tool", "routing.guide2") not in names  # a contact
    assert pair_key("left/tool", "box@left") not in names  # held by its gripper
    assert pair_key("left/tool", "routing.guide2") in names
    assert pair_key("box@left", "right/tool") in names  # a held object is its arm's
    assert pair_key("left/shoulder_link", "table") not in names  # the cell's layout
    assert not any(n.startswith("left/") and m.startswith("left/") for n, m in names)


def test_the_gate_refuses_a_segment_under_the_clearance_in_plan_terms() -> None:
    world, cell, checker = cable_cell()
    env = compiled()[1].report["clearance"]["environment"]
    arms = compiled()[1].report["clearance"]["arms"]
    limit = round(env["distance_m"] + 0.0005, 4)
    assert arms["distance_m"] >= limit  # only the environment falls short
    c = Compiler(world, cell, checker, home(cell), clearance=0.0)
    c.add(ready())
    c.clearance = limit
    with pytest.raises(StepError) as e:
        c.add(left_line())
    a, b = env["pair"]
    assert str(e.value.problems[0].message) == (
        f"step 2 (left line): the {a.split('/')[0]} arm passes "
        f"{env['distance_m'] * 1000:.1f} mm from the environment ({a}, {b}) "
        f"at t = {env['time_s']:.1f} s; the cell's clearance is {limit * 1000:g} mm"
    )
    assert len(c.segments) == 1  # the compiler is as it was


def test_the_arms_shortfall_says_how_far_apart() -> None:
    from cellengine.motion.clearance import Clearance, Closest

    short = Clearance(
        Closest(0.0037, ("left/wrist_3_link", "right/upper_arm_link"), 12.3, "left"), None
    )
    ((_, why),) = short.shortfalls(0.01)
    assert why == (
        "the arms pass 3.7 mm apart (left/wrist_3_link, right/upper_arm_link) at t = 12.3 s; "
        "the cell's clearance is 10 mm"
    )
    assert short.shortfalls(0.0037) == []


def test_report_json_carries_each_segments_clearance_and_the_least() -> None:
    _, cell, _ = cable_cell()
    first, done = compiled()
    from cellengine.program import Program

    program = Program(cell.joint_names, (first, done), ())
    data = report_data(program, cell)
    for s, cs in zip(data["segments"], (first, done), strict=True):
        assert s["clearance"] == cs.report["clearance"]
        assert set(s["clearance"]) == {"arms", "environment"}
        assert set(s["clearance"]["arms"]) == {"distance_m", "pair", "time_s"}
    for kind in KINDS:
        least = data["totals"]["clearance"][kind]
        i = min((0, 1), key=lambda k: data["segments"][k]["clearance"][kind]["distance_m"])
        assert least == {
            **data["segments"][i]["clearance"][kind],
            "segment": i,
            "label": data["segments"][i]["label"],
        }


def test_a_transit_keeps_the_default_clearance_in_a_cell_set_lower() -> None:
    """The left arm to a pose whose straight line passes 4.7 mm from the right arm: the cell's
    1 mm would let the line pass; the transit keeps 10 mm (the gate at 10 mm accepts it)."""
    from tests.motion.test_margins import A, B

    world, cell, checker = cable_cell()
    goal = cell.arms["left"].fk(np.array(B[:6]))
    c = Compiler(world, cell, checker, np.array(A), clearance=0.001)
    assert c.transit_clearance == 0.010
    transit = Segment(0, "left over", (ArmPath("left", "transit", goal[None]),))
    seg = c.add(transit)
    assert seg.report["clearance"]["arms"]["distance_m"] >= 0.010
    strict = Compiler(world, cell, checker, np.array(A), clearance=0.010)
    arms = strict.add(transit).report["clearance"]["arms"]  # the gate at 10 mm lets it pass
    assert arms["distance_m"] == pytest.approx(seg.report["clearance"]["arms"]["distance_m"])


def test_a_motion_leaving_where_the_step_before_worked_is_held_to_its_start_distance() -> None:
    """The left fingertips taken down to 12 mm over the table beyond the routing plate's
    edge (y = 0.21 m; the cell's clearance 0 for it), then the clearance raised to 30 mm:
    going back up leaves the table, never closer than where it starts, and passes; moving
    5 cm sideways down there does not."""
    world, cell, checker = cable_cell()
    lx, ly = LEFT_READY[0], 0.30
    low = (lx, ly, 0.012)
    down = Segment(1, "down", (ArmPath("left", "cartesian", line(LEFT_READY, low)),))
    c = Compiler(world, cell, checker, home(cell), clearance=0.0)
    c.add(ready())
    env = c.add(down).report["clearance"]["environment"]
    assert env["pair"][1] == "table" and env["distance_m"] < 0.03
    c.clearance = 0.03
    mark = c.mark()
    up = Segment(2, "up", (ArmPath("left", "cartesian", line(low, LEFT_READY)),))
    c.add(up)  # leaving: passes
    c.restore(mark)
    aside = Segment(2, "aside", (ArmPath("left", "cartesian", line(low, (lx + 0.05, ly, 0.012))),))
    with pytest.raises(StepError, match=r"step 3 \(aside\): the left arm passes .* \(left/.*, "
                       r"table\) .* the cell's clearance is 30 mm"):  # fmt: skip
        c.add(aside)
