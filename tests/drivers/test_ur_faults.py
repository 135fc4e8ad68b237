"""Each fault the issue names, injected mid-run on one arm of two emulated UR controllers:
the run stops both arms (the healthy one is told to stop too), exits 3 naming the fault,
journals it, and `--resume` completes the plan once the fault is cleared, every segment run
once. (The protective stop on the right arm is in test_ur_emulated.py, on the whole
straight plan.)

A short plan (pick the cable, place its connector: 10 s of motion) keeps each case brief."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import skills.cable  # noqa: F401  (registers the cable skills)
from cellengine.pipeline import compile_plan
from tests.drivers.urcell import journal, run_cli, start
from tests.emulate.harness import Emulator, dashboard, wait_for

SHORT = """cell: cell.yaml
objects: objects.yaml
execution: split
steps:
  - skill: PickCable
    cable: cable1
    from: [holder.comb_a, holder.comb_b]
  - skill: PlaceConnector
    cable: cable1
    guide: routing.connector
"""
AT = 5.0  # s after the first RTDE connection: a second or two into the motion

# (emulated fault, the driver's fault kind, what the message says), each on either arm; the
# protective stop on the right arm is in test_ur_emulated.py
FAULTS = [
    ("protective_stop", "protective_stop", "protective stop"),
    ("emergency_stop", "emergency_stop", "emergency stop"),
    ("frozen", "tracking", "does not follow"),
    ("drop", "connection", "connection to arm '{arm}'"),
    ("kill", "connection", "connection to arm '{arm}'"),
]
CASES = [
    (inject, arm, kind, says.format(arm=arm))
    for inject, kind, says in FAULTS
    for arm in ("left", "right")
    if (inject, arm) != ("protective_stop", "right")
]


@pytest.mark.parametrize(("inject", "arm", "kind", "says"), CASES)
def test_a_fault_stops_both_arms_and_resume_completes_the_plan(
    tmp_path: Path,
    emulated: tuple[Path, list[str], list[Emulator]],
    inject: str,
    arm: str,
    kind: str,
    says: str,
) -> None:
    folder, hosts, started = emulated
    plan = folder / "plan_short.yaml"
    plan.write_text(SHORT)
    program = compile_plan(plan).program
    q0 = program.segments[0].trajectory.q[0]
    i = ("left", "right").index(arm)
    host, other = hosts[i], hosts[1 - i]
    fault = ("--fault", f"{host}@{AT:g}:{inject}")
    if inject == "kill":  # a controller of its own, so that killing it spares the other
        start([other], q0[6 * (1 - i) : 6 * (2 - i)], started)
        faulty = start([host], q0[6 * i : 6 * i + 6], started, *fault)
    else:
        faulty = start(hosts, q0, started, *fault)

    run = tmp_path / "run"
    result = run_cli(str(plan), "--out", str(run), timeout=120)
    assert result.returncode == 3, result.stderr[-2000:]
    assert says in result.stderr and "every arm stopped" in result.stderr, result.stderr
    entries = journal(run)
    stopped = next(e for e in entries if e["entry"] == "fault")["fault"]
    assert stopped["kind"] == kind and stopped["arm"] == arm
    assert stopped["details"]["stop_commands_s"] >= 0
    done = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert 0 < len(done) < len(program.segments)  # mid-run
    # the healthy arm was told to stop by the driver, not by its watchdog
    log = (started[0] if inject == "kill" else faulty).stderr()
    assert f"{other}: stopJ" in log, log[-2000:]

    if inject == "kill":  # the controller comes back where its arm stopped
        q_stop = np.array(stopped["q"][6 * i : 6 * i + 6])
        started.append(Emulator([host], "--q0", f"{host}=" + ",".join(map(str, q_stop))))
    else:
        assert faulty.fault(host, "clear") == "ok"
    if inject == "emergency_stop":  # the operator powers the arm on and releases the brakes
        dashboard(host, "power on")
        wait_for(lambda: "IDLE" in dashboard(host, "robotmode")[0], what="power on")
        dashboard(host, "brake release")
        wait_for(lambda: "RUNNING" in dashboard(host, "robotmode")[0], what="brake release")
    again = run_cli(str(plan), "--resume", str(run), timeout=120)
    assert again.returncode == 0, again.stderr[-2000:]
    entries = journal(run)
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(len(program.segments)))  # each once, in order
    assert entries[-1]["entry"] == "end"
    last = next(e for e in reversed(entries) if e["entry"] == "finished")
    assert np.allclose(last["q"], program.segments[-1].trajectory.q[-1], atol=0.005)
