"""report.json's ``run`` from what ended a run and from its journal."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from cellengine.drivers.fault import DriverFault, DriverRefused, Fault
from cellengine.pipeline import Compiled, compile_plan
from cellengine.runner.ran import outcome_of, run_summary, runtime_choices
from tests.conftest import CELLS

LAB_PLAN = CELLS / "lab_bench" / "plan_pour_heavier.yaml"


def test_the_outcome_of_what_ended_the_run() -> None:
    assert outcome_of(None) == ("completed", None, None)
    assert outcome_of(KeyboardInterrupt()) == ("interrupted", None, "interrupted (Ctrl-C)")
    # an interrupt outside the driver's loop: the driver's fault says when it stopped the arms
    at = Fault("interrupted", "interrupted; both arms stopped", time=0.75)
    assert outcome_of(KeyboardInterrupt(), at) == (
        "interrupted",
        at.to_json(),
        "interrupted (Ctrl-C)",
    )
    stopped = Fault("interrupted", "interrupted at t = 1.500 s; both arms stopped", time=1.5)
    kind, fault, message = outcome_of(DriverFault("sim", stopped))
    assert (kind, message) == ("interrupted", stopped.message)
    assert fault == stopped.to_json()
    frozen = Fault("tracking", "joint off", arm="left", joint="left_elbow_joint", time=2.25)
    kind, fault, message = outcome_of(DriverFault("sim", frozen))
    assert (kind, message) == ("fault", "joint off")
    assert fault is not None and (fault["kind"], fault["arm"], fault["time"]) == (
        "tracking",
        "left",
        2.25,
    )
    assert outcome_of(DriverRefused("sim", "too far")) == ("error", None, "sim driver: too far")


@pytest.fixture(scope="module")
def lab() -> Compiled:
    return compile_plan(LAB_PLAN)


def test_runtime_choices_by_objects_yaml_until_weighed(lab: Compiled) -> None:
    """Nothing weighed: objects.yaml's masses (vial2 42 g, vial1 30 g); one weighed: still the
    file's for the other; both: the readings'."""
    (choice, _) = runtime_choices(lab, {})
    assert (choice["step"], choice["chose"], choice["by"]) == (2, "vial2", "objects.yaml")
    (choice, _) = runtime_choices(lab, {"vial1": 0.050})
    assert (choice["chose"], choice["by"]) == ("vial1", "objects.yaml")
    (choice, _) = runtime_choices(lab, {"vial1": 0.020, "vial2": 0.021})
    assert (choice["chose"], choice["by"]) == ("vial2", "measured")


def test_the_summary_reads_the_journal_since_its_last_start(tmp_path: Path, lab: Compiled) -> None:
    """An earlier run's entries are not this run's; a torn last line is skipped."""
    lines = [
        {"entry": "start"},
        {"entry": "measured", "step": 0, "object": "vial1", "arm": "robot1", "mass_kg": 0.5},
        {"entry": "end"},
        {"entry": "start"},
        {"entry": "sent", "segment": 0, "label": "a"},
        {"entry": "finished", "segment": 0, "label": "a"},
        {"entry": "measured", "step": 1, "object": "vial2", "arm": "robot1", "mass_kg": 0.04},
        {"entry": "fault", "fault": {"kind": "tracking"}},
        {"entry": "resume", "from_segment": 1, "label": "b"},
        {"entry": "sent", "segment": 1, "label": "b"},
        {"entry": "finished", "segment": 1, "label": "b"},
        {"entry": "replanned"},
        {"entry": "sent", "segment": 2, "label": "c"},
    ]
    text = "".join(json.dumps(e) + "\n" for e in lines) + '{"entry": "fini'
    (tmp_path / "journal.jsonl").write_text(text)
    run = run_summary(lab, "sim", tmp_path, KeyboardInterrupt())
    assert (run["outcome"], run["message"], run["fault"]) == (
        "interrupted",
        "interrupted (Ctrl-C)",
        None,
    )
    assert run["segments_finished"] == 2
    assert run["stopped_in"] == {"segment": 2, "label": "c"}
    assert run["resumed"] == [{"from_segment": 1, "label": "b"}]
    assert run["replanned"] == 1
    assert run["measured"] == [{"step": 1, "object": "vial2", "arm": "robot1", "mass_kg": 0.04}]
    # no report in the folder: the program's (both robots at once: their streams')
    assert lab.program.streams and run["segments"] == len(lab.program.streams)
    running = run_summary(lab, "sim", tmp_path, running=True)
    assert (running["outcome"], running["stopped_in"]) == ("running", None)
