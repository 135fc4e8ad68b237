"""report_data: per step and segment figures from a hand-made program on the cable cell."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cellengine.motion.gate import GateReport, Violation
from cellengine.program import CompiledSegment, Program
from cellengine.report import report_data
from cellengine.report.data import step_label
from cellengine.report.distance import ArmDistance
from cellengine.report.jsonable import jsonable
from tests.report.programs import cable_cell, sample_program


@pytest.fixture(scope="module")
def data() -> dict:
    _, cell = cable_cell()
    return report_data(sample_program(cell), cell, extra={"plan": "plan_one_turn.yaml"})


def test_totals(data: dict) -> None:
    t = data["totals"]
    assert t["cycle_time_s"] == pytest.approx(6.0)
    # segment 0 ran the joint merge (published: 1.5 s longer), segment 2 the published one
    # (joint: 0.5 s shorter); segment 1 is one arm's
    assert t["cycle_time_by_merge_s"] == {
        "joint": pytest.approx(5.5),
        "published": pytest.approx(7.5),
    }
    assert (t["segments"], t["steps"], t["events"]) == (3, 2, 3)
    assert t["planning_time_s"] == pytest.approx(0.175)
    assert t["checks_passed"] is False  # segment 2 reports a failed check
    assert t["min_arm_distance_m"] == min(
        s["min_arm_distance_m"] for s in data["segments"] if s["min_arm_distance_m"] is not None
    )
    assert data["arms"] == ["left", "right"]
    assert data["plan"] == "plan_one_turn.yaml"
    assert data["format"] == "cellengine.report/1"


def test_segment_figures(data: dict) -> None:
    s0, s1, s2 = data["segments"]
    assert (s0["index"], s0["step"], s0["label"]) == (0, 0, "PickCable: approach")
    assert (s0["strategy"], s0["merge"]) == ("split", "joint")
    assert (s0["start_s"], s0["end_s"], s0["duration_s"]) == pytest.approx((0.0, 2.0, 2.0))
    assert s0["arms"] == {"left": "cartesian", "right": "cartesian"}
    assert s0["cartesian_fraction"] == {"left": 1.0, "right": 0.97}
    assert s0["planning_time_s"] == 0.125
    assert s0["checks_passed"] is True  # {"gate": True, ...}: non-bool entries ignored
    # a transit arm has no Cartesian fraction; a number applies to every Cartesian arm
    assert s1["cartesian_fraction"] == {"left": None}
    assert s2["cartesian_fraction"] == {"left": 0.5, "right": 0.5}
    assert s2["strategy"] == "sync" and s2["merge"] == "published"
    assert s2["checks_passed"] is False
    assert s1["before"] == [
        {"arm": "left", "mode": "grasp", "holds": "cable1.connector"},
        {"arm": "right", "mode": "grasp", "holds": "cable1"},
    ]
    assert s2["after"] == [{"arm": "right", "mode": "open", "holds": None}]
    assert s2["facts"] == {"guide": "routing.guide2", "slot": [0.3, -0.2, 0.065]}


def test_executor_keys_pass_through(data: dict) -> None:
    s0, _, s2 = data["segments"]
    assert s0["custom"] == [1.0, 2.0]  # numpy made plain
    assert s0["fraction"] == {"left": 1.0, "right": 0.97}
    assert s0["checks"] == {"gate": True, "gate_samples": 2001, "keep_distance": None}
    # the executor's richer keep_distance wins over the segment's own arm pair
    assert s0["keep_distance"] == {"arms": ["left", "right"], "distance_m": 0.3}
    assert s2["keep_distance"] == ["left", "right"]
    assert s2["nan_figure"] is None  # JSON has no NaN
    json.dumps(data, allow_nan=False)


def test_reported_distance_is_kept(data: dict) -> None:
    s2 = data["segments"][2]
    assert s2["min_arm_distance_m"] == 0.2345
    assert s2["closest_pair"] == ["left/tool", "right/tool"]
    assert s2["distance_source"] == "executor"


def test_missing_distance_is_measured_between_the_arms(data: dict) -> None:
    """Segment 0 reports none: measured every 10 ms; within 1 mm of a 1 ms search."""
    _, cell = cable_cell()
    s0 = data["segments"][0]
    assert s0["distance_source"] == "computed"
    a, b = s0["closest_pair"]
    assert a.split("/")[0] != b.split("/")[0]
    traj = sample_program(cell).segments[0].trajectory
    q, _, _ = traj.sample(np.linspace(traj.start_time, traj.end_time, 2001))
    dense = ArmDistance(cell).minimum(q)
    assert dense is not None
    assert s0["min_arm_distance_m"] >= dense[0] - 1e-9
    assert s0["min_arm_distance_m"] == pytest.approx(dense[0], abs=1e-3)
    assert 0.0 < s0["min_arm_distance_m"] < 2.0


def test_steps(data: dict) -> None:
    st0, st1 = data["steps"]
    assert (st0["step"], st0["label"], st0["segments"]) == (0, "PickCable", [0, 1])
    assert (st1["step"], st1["label"], st1["segments"]) == (1, "RouteCable guide2", [2])
    assert (st0["start_s"], st0["end_s"], st0["duration_s"]) == pytest.approx((0.0, 3.0, 3.0))
    assert st0["planning_time_s"] == pytest.approx(0.175)
    assert st0["checks_passed"] is True and st1["checks_passed"] is False
    assert st0["strategies"] == ["split"]
    assert st0["min_arm_distance_m"] == min(
        data["segments"][k]["min_arm_distance_m"] for k in (0, 1)
    )


def test_step_labels_and_no_cell() -> None:
    _, cell = cable_cell()
    out = report_data(sample_program(cell), step_labels={1: "route through guide2"})
    assert [s["label"] for s in out["steps"]] == ["PickCable", "route through guide2"]
    # without the cell nothing is measured: only the reported distance is known
    assert [s["min_arm_distance_m"] for s in out["segments"]] == [None, None, 0.2345]
    assert out["arms"] == ["left", "right"]


def test_extra_may_not_replace_a_key() -> None:
    _, cell = cable_cell()
    with pytest.raises(ValueError, match="'totals'"):
        report_data(sample_program(cell), extra={"totals": 1})


def test_gate_report_gives_checks_and_distance() -> None:
    _, cell = cable_cell()
    program = sample_program(cell)
    cs = program.segments[1]
    failing = GateReport((Violation("velocity", 1.5, "left_elbow_joint", 4.0, 3.14),), 100)
    gate = GateReport((), 1000, 0.321, ("left/tool", "right/forearm_link"))
    outs = []
    for g in (gate, failing):
        seg = CompiledSegment(cs.segment, "split", cs.trajectory, {"gate": g})
        outs.append(report_data(Program(program.joint_names, (seg,), ()))["segments"][0])
    assert outs[0]["checks_passed"] is True
    assert outs[0]["min_arm_distance_m"] == 0.321
    assert outs[0]["closest_pair"] == ["left/tool", "right/forearm_link"]
    assert outs[0]["gate"]["ok"] is True
    assert outs[1]["checks_passed"] is False
    assert outs[1]["gate"]["violations"] == [str(failing.violations[0])]


def test_empty_program() -> None:
    out = report_data(Program(("a",), (), ()))
    assert out["totals"]["cycle_time_s"] == 0.0
    assert out["steps"] == [] and out["segments"] == []


def test_jsonable() -> None:
    assert jsonable({1: (np.float32(0.5), np.int64(3), {"b", "a"}, math.inf)}) == {
        "1": [0.5, 3, ["a", "b"], None]
    }
    assert jsonable(np.array([[1, 2]])) == [[1, 2]]
    assert jsonable(np.bool_(True)) is True


@pytest.mark.parametrize(
    ("labels", "name"),
    [
        (["RouteCable guide2: lift", "RouteCable guide2: insert"], "RouteCable guide2"),
        (["RouteCable routing.guide1: a", "RouteCable routing.guide2: b"], "RouteCable"),
        (["RouteCable guide1: a", "cable1: release and retract"], "RouteCable"),
        (["PickCable: approach"], "PickCable"),
        (["lift"], "lift"),
        ([""], ""),
    ],
)
def test_step_label(labels: list[str], name: str) -> None:
    assert step_label(labels) == name
