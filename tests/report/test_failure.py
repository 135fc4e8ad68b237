"""The report of a failed plan (report/failure.py) on hand-made failures: report.json's
``failure`` section and the replay's failing poses, no compile."""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from cellengine.execute.failure import FailedAt, Failure
from cellengine.program import ArmPath, Program, Segment
from cellengine.report.failure import Found, failure_texts
from cellengine.report.replay import placements
from tests.report.programs import cable_cell, home, sample_program

PAIR = ("left/tool", "routing.guide1#2")  # an element of two boxes: its second


def _found() -> tuple[Program, list[Found]]:
    """Two failures after sample_program's segments: a collision in step 2's segment
    'insert' (the left arm moved 0.2 rad), and step 3 refused by its skill."""
    _, cell = cable_cell()
    program = sample_program(cell)
    q = home(cell)
    q[0] += 0.2
    segment = Segment(
        2, "RouteCable guide1: insert", (ArmPath("left", "transit", np.eye(4)[None]),)
    )
    at = FailedAt("collision", q, PAIR, 7.5, {"left": np.array([0.43, -0.06, 0.065])})
    return program, [
        Found(
            ("plan.yaml:9:5: step 3 (RouteCable guide1: insert): collision",),
            Failure(2, segment, at, program),
        ),
        Found(("plan.yaml:12:5: steps[3] RouteCable: refused",), Failure(3)),
    ]


def _texts() -> tuple[dict[str, Any], str]:
    world, cell = cable_cell()
    program, found = _found()
    texts = failure_texts(
        program,
        world,
        cell,
        found,
        {"plan": "plan.yaml"},
        step_labels={2: "RouteCable cable1"},
        title="t",
    )
    return json.loads(texts["report.json"]), texts["report.html"]


def test_report_json_names_each_failure_where_it_stopped() -> None:
    report, _ = _texts()
    _, cell = cable_cell()
    q = home(cell)
    q[0] += 0.2
    assert report["failure"] == {
        "compiled_segments": 3,
        "failures": [
            {
                "messages": ["plan.yaml:9:5: step 3 (RouteCable guide1: insert): collision"],
                "step": 2,
                "step_label": "RouteCable cable1",
                "segment": "RouteCable guide1: insert",
                "segment_index": 3,
                "kind": "collision",
                "pair": list(PAIR),
                "q": q.tolist(),
                "time_s": 7.5,
                "targets": {"left": [0.43, -0.06, 0.065]},
            },
            {
                "messages": ["plan.yaml:12:5: steps[3] RouteCable: refused"],
                "step": 3,
                "step_label": None,
                "segment": None,
                "segment_index": None,
                "kind": "refused",
                "pair": None,
                "q": None,
                "time_s": None,
                "targets": {},
            },
        ],
    }
    # the compiled segments as any report has them; the plan's checks did not pass
    assert len(report["segments"]) == 3 and report["plan"] == "plan.yaml"
    assert report["totals"]["checks_passed"] is False


def test_the_replay_has_the_failing_pose_with_the_pair_highlighted() -> None:
    _, cell = cable_cell()
    _, found = _found()
    _, html = _texts()
    data = json.loads(
        html.split("id='ce-data'>", 1)[1].split("</script>", 1)[0].replace("\\u003c", "<")
    )
    (pose,) = data["replay"]["failure"]["poses"]  # the refused step has no pose
    assert (pose["failure"], pose["kind"], pose["pair"]) == (0, "collision", list(PAIR))
    assert [link["name"] for link in pose["links"] if link["highlight"]] == ["left/tool"]
    assert pose["statics"] == ["routing.guide1"]  # the element's mesh, drawn as one
    assert pose["targets"] == {"left": [0.43, -0.06, 0.065]}
    # the links and the TCPs at the failing configuration
    q = found[0].failure.at.q  # type: ignore[union-attr]
    _, tcp = placements(cell, q[None])
    for arm in cell.arms:
        np.testing.assert_allclose(pose["tcp"][arm], tcp[arm][0], atol=1e-4)
    tool = next(link for link in pose["links"] if link["name"] == "left/tool")
    assert tool["fixed"] is True and len(tool["points"]) == tool["stride"]  # one sample
