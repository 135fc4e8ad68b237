"""Issue 4, "What the output must show", on the compiled Program of each reference plan, and of
the shared REMODEL sample imported with the reference robots, with each execution strategy:
joint limits at 1 ms, every routed guide crossed by the cable between the fingertips, constant
hand distance on the circular moves, the connector at its keypoint; and each program played on
the simulated cell."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.cable  # noqa: F401  (the real skills package registers the cable skills)
from cellengine.cli import main
from cellengine.drivers.play import play
from cellengine.drivers.sim import SimDriver
from cellengine.errors import InputError
from cellengine.motion.trajectory import concatenate
from cellengine.pipeline import Compiled, compile_plan
from cellengine.program import Program
from tests.conftest import CELLS, REMODEL

DT = 1e-3
ROUTING = CELLS / "cable_routing"
STRATEGIES = ("split", "sync", "async")
PLANS = {
    "straight": ("routing.guide1", "routing.guide2", "routing.guide3"),
    "two_turns": ("routing.guide1", "routing.guide5", "routing.guide6", "routing.guide7"),
    "one_turn": ("routing.guide1", "routing.guide2", "routing.guide4"),
    "remodel": ("platform.J3.1", "platform.J4.1", "platform.J1.1", "platform.J2.1"),
}
# The REMODEL route runs along the platform's -x and its connector goes in with the left arm
# (the sequence's 'J8.1.L'): a yaw of 90 deg lays the route along the cell's -y, from the left
# arm's side to the right's, and the shift puts it in front of both arms, as in cable_routing.
REMODEL_POSE = "250 380 0 0 0 90"

_CACHE: dict[tuple[str, str], Compiled | InputError] = {}


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """The plan file of each case; the REMODEL sample imported into a temporary folder."""
    dest = tmp_path_factory.mktemp("remodel") / "cell"
    assert main(["import", "remodel", str(REMODEL), str(dest), f"--pose={REMODEL_POSE}"]) == 0
    out = {plan: ROUTING / f"plan_{plan}.yaml" for plan in PLANS if plan != "remodel"}
    return {**out, "remodel": dest / "plan.yaml"}


def _compiled(files: dict[str, Path], plan: str, strategy: str) -> Compiled:
    key = (plan, strategy)
    if key not in _CACHE:
        try:
            _CACHE[key] = compile_plan(files[plan], strategy)
        except InputError as e:
            _CACHE[key] = e
    hit = _CACHE[key]
    if isinstance(hit, InputError):
        raise hit
    return hit


def _cases() -> list[object]:
    return [
        pytest.param(plan, strategy, id=f"{plan}-{strategy}")
        for plan in PLANS
        for strategy in STRATEGIES
    ]


def _times(t0: float, t1: float) -> np.ndarray:
    n = max(2, math.ceil((t1 - t0) / DT) + 1)
    return np.linspace(t0, t1, n)


def _tips(c: Compiled, q: np.ndarray, arms: tuple[str, str]) -> tuple[np.ndarray, np.ndarray]:
    parts = c.cell.split(q)
    a, b = (c.cell.arms[arm].fk(parts[arm])[:3, 3] for arm in arms)
    return np.asarray(a), np.asarray(b)


def _mode_at(program: Program, arm: str, t: float) -> tuple[str | None, str | None]:
    mode: tuple[str | None, str | None] = (None, None)
    for e in program.events:
        if e.event.arm == arm and e.time <= t + 1e-9:
            mode = (e.event.mode, e.event.holds)
    return mode


def _point_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    s = float(np.clip((p - a) @ ab / float(ab @ ab), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + s * ab)))


@pytest.mark.parametrize(("plan", "strategy"), _cases())
def test_limits_at_1ms(files: dict[str, Path], plan: str, strategy: str) -> None:
    c = _compiled(files, plan, strategy)
    traj = concatenate([s.trajectory for s in c.program.segments])
    assert tuple(traj.joint_names) == tuple(c.cell.joint_names)
    q, qd, _ = traj.sample(_times(traj.start_time, traj.end_time))
    lim = c.cell.limits
    tol = 1e-6
    assert np.all(q >= lim.lower - tol), "joint position below its lower limit"
    assert np.all(q <= lim.upper + tol), "joint position above its upper limit"
    assert np.all(np.abs(qd) <= lim.velocity + tol), "joint velocity over its limit"


@pytest.mark.parametrize(("plan", "strategy"), _cases())
def test_every_guide_holds_the_cable(files: dict[str, Path], plan: str, strategy: str) -> None:
    c = _compiled(files, plan, strategy)
    found: list[str] = []
    last = -math.inf
    for seg in c.program.segments:
        f = seg.segment.facts
        if "routing_arm" not in f:
            continue
        guide, gap = str(f["guide"]), float(f["gap"])
        slot = np.asarray(c.world.pose(guide)[:3, 3], dtype=float)
        axis = np.asarray(c.world.pose(guide)[:3, 0], dtype=float)
        arms = (str(f["routing_arm"]), str(f["other_arm"]))
        traj = seg.trajectory
        ok_at = None
        for t in _times(traj.start_time, traj.end_time):
            mode, holds = _mode_at(c.program, arms[0], float(t))
            if mode not in ("grasp", "slide") or holds is None:
                continue
            q, _, _ = traj.sample(np.array([t]))
            a, b = _tips(c, q[0], arms)
            d = b - a
            angle = math.degrees(math.acos(min(1.0, abs(float(d @ axis)) / np.linalg.norm(d))))
            if _point_segment(slot, a, b) <= gap / 2.0 and angle <= 15.0:
                ok_at = float(t)
                break
        assert ok_at is not None, f"{guide}: the cable never lies through its slot"
        assert ok_at > last
        last = ok_at
        found.append(guide)
    assert tuple(found) == PLANS[plan]


@pytest.mark.parametrize(("plan", "strategy"), _cases())
def test_circular_moves_keep_the_distance(files: dict[str, Path], plan: str, strategy: str) -> None:
    c = _compiled(files, plan, strategy)
    n = 0
    for seg in c.program.segments:
        pair = seg.segment.keep_distance
        if pair is None:
            continue
        n += 1
        traj = seg.trajectory
        qs, _, _ = traj.sample(_times(traj.start_time, traj.end_time))
        dist = [float(np.linalg.norm(np.subtract(*_tips(c, q, pair)))) for q in qs]
        assert max(dist) - min(dist) <= 1e-3, f"{seg.segment.label}: hand distance varies"
    assert n >= 3 * len(PLANS[plan])


@pytest.mark.parametrize(("plan", "strategy"), _cases())
def test_connector_reaches_its_keypoint(files: dict[str, Path], plan: str, strategy: str) -> None:
    c = _compiled(files, plan, strategy)
    placed = [s for s in c.program.segments if "connector_arm" in s.segment.facts]
    assert placed
    seg = placed[0]
    arm = str(seg.segment.facts["connector_arm"])
    target = np.asarray(c.world.pose(str(seg.segment.facts["guide"]))[:3, 3], dtype=float)
    traj = seg.trajectory
    qs, _, _ = traj.sample(_times(traj.start_time, traj.end_time))
    best = min(
        float(np.linalg.norm(c.cell.arms[arm].fk(c.cell.split(q)[arm])[:3, 3] - target)) for q in qs
    )
    assert best <= 1e-3


@pytest.mark.parametrize(("plan", "strategy"), _cases())
def test_runs_on_the_simulated_cell(files: dict[str, Path], plan: str, strategy: str) -> None:
    """Played on the simulated cell at its 2 ms servo period: every segment completes, the
    arms end where the program ends, every gripper event is applied, both hands have held
    the cable, and both let it go at the end (Algorithm 1's release and retract)."""
    c = _compiled(files, plan, strategy)
    joints = {name: arm.joint_names for name, arm in c.cell.arms.items()}
    q0 = c.program.segments[0].trajectory.q[0]
    with SimDriver(c.world.cell, joints, objects=c.world.objects, q0=q0) as driver:
        driver.configure()
        driver.activate()
        played = play(driver, c.program)
        assert len(played) == len(c.program.segments)
        assert all(p.completed for p in played)
        end = c.program.segments[-1].trajectory.q[-1]
        assert np.allclose(driver.joint_state(), end, atol=1e-9)
        applied = [e for p in played for e in p.events]
        assert len(applied) == len(c.program.events)
        assert all(e.done for e in applied)
        (cable,) = c.world.objects.cables
        for arm in c.cell.arms:
            assert any(e.arm == arm and (e.mode, e.holds) == ("grasp", cable) for e in applied)
            assert driver.gripper(arm) == ("open", None)
        driver.deactivate()


def test_every_plan_file_exists(files: dict[str, Path]) -> None:
    assert sorted(files) == sorted(PLANS)
    for path in files.values():
        assert path.is_file()
