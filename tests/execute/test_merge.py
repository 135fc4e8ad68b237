"""Merging two arms' trajectories onto one time axis: exact, published, joint."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.execute import Compiler
from cellengine.execute.merge import follow, on_one_axis, published
from cellengine.execute.retime import jerk_limits, thinned, timed
from cellengine.execute.strategies import Part, solve_segment
from cellengine.motion.trajectory import Trajectory
from cellengine.program import CompiledSegment, Segment
from tests.execute.scenes import cable_cell, home, ready, reference_segments, synchronised

TIMING_SLACK = 5e-3  # the timing module's own: a smoothed optimum may lose this share


def after_ready(segment: Segment, strategy: str = "sync") -> CompiledSegment:
    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell), strategy)  # type: ignore[arg-type]
    c.add(ready())
    return c.add(segment)


def solved(segment: Segment, strategy: str = "sync") -> tuple[np.ndarray, Part]:
    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell), strategy)  # type: ignore[arg-type]
    c.add(ready())
    (part,) = solve_segment(cell, checker, segment, c.q, strategy)  # type: ignore[arg-type]
    return c.q, part


def alone(part: Part) -> dict[str, Trajectory]:
    _, cell, _ = cable_cell()
    return {
        a: timed(r, cell.arms[a].limits, cell.arms[a].joint_names) for a, r in part.rows.items()
    }


def within(traj: Trajectory) -> bool:
    _, cell, _ = cable_cell()
    peaks, lim = traj.peaks(), cell.limits
    return bool(
        (peaks.velocity <= lim.velocity * (1 + 1e-6)).all()
        and (peaks.acceleration <= lim.acceleration * (1 + 1e-6)).all()
        and (peaks.jerk <= jerk_limits(lim) * (1 + 1e-6)).all()
    )


def test_on_one_axis_is_exact() -> None:
    _, cell, _ = cable_cell()
    q, part = solved(synchronised()["corner"], "split")
    own = alone(part)
    merged = on_one_axis(cell, q, own, {"left": 0.0, "right": 0.3})
    t = np.linspace(0.0, merged.end_time, 997)
    Q, V, A = merged.sample(t)
    for arm, start in (("left", 0.0), ("right", 0.3)):
        q_own, v_own, a_own = own[arm].sample(t - start)
        cols = cell.slices[arm]
        assert np.allclose(Q[:, cols], q_own, atol=1e-9)
        assert np.allclose(V[:, cols], v_own, atol=1e-9)
        assert np.allclose(A[:, cols], a_own, atol=1e-7)


def test_published_follows_the_slower_arm_place_by_place() -> None:
    _, cell, _ = cable_cell()
    q, part = solved(synchronised()["parallel"], "split")
    own = alone(part)
    lead = max(own, key=lambda a: own[a].duration)
    merged = published(cell, q, own, part.rows)
    assert lead == "left" and within(merged)
    # the slower arm keeps its own timing exactly when nothing had to be slowed
    assert merged.duration == pytest.approx(own[lead].duration, abs=1e-6)
    assert np.array_equal(merged.q[:, cell.slices[lead]], own[lead].q)
    # the other arm is at the same fraction of its own path as the slower arm of its own
    right = merged.q[:, cell.slices["right"]]
    path = thinned(part.rows["right"])
    length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
    covered = np.linalg.norm(right - path[0], axis=1)  # a nearly straight joint path
    left = merged.q[:, cell.slices["left"]]
    lpath = thinned(part.rows["left"])
    llength = np.linalg.norm(np.diff(lpath, axis=0), axis=1).sum()
    lcovered = np.linalg.norm(left - lpath[0], axis=1)
    assert np.allclose(covered / length, lcovered / llength, atol=0.02)


def test_published_is_slowed_to_the_limits_where_the_faster_arm_cannot_follow() -> None:
    _, cell, _ = cable_cell()
    q, part = solved(synchronised()["corner"], "split")
    own = alone(part)
    merged = published(cell, q, own, part.rows)
    assert within(merged)
    assert merged.duration > 1.1 * max(t.duration for t in own.values())


def test_follow_on_a_stop_of_the_leader() -> None:
    """Following a leader through a standstill in mid-path keeps velocities continuous."""
    _, cell, _ = cable_cell()
    q, part = solved(synchronised()["parallel"], "split")
    own = alone(part)
    fraction = np.linspace(0.0, 1.0, len(thinned(part.rows["right"])))
    merged = follow(
        cell, q, own["left"], "left", {"right": (thinned(part.rows["right"]), fraction)}
    )
    assert within(merged)


@pytest.mark.parametrize("strategy", ["sync", "split"])
def test_joint_merge_no_slower_than_published_and_near_the_bound(strategy: str) -> None:
    """Parallel lines, timed together: the shorter line's arm can follow the longer one's own
    timing, which no timing of the pair can beat."""
    r = after_ready(synchronised()["parallel"], strategy).report
    joint, pub = r["durations_s"]["joint"], r["durations_s"]["published"]
    assert joint <= pub * (1 + 1e-9)
    assert joint <= 1.05 * r["jerk_limited_bound_s"]
    assert r["time_optimal_bound_s"] < r["jerk_limited_bound_s"]  # jerk limits cost time
    assert r["duration_s"] == pytest.approx(joint)


@pytest.mark.parametrize("strategy", ["sync", "split"])
def test_joint_merge_much_faster_where_published_must_slow_down(strategy: str) -> None:
    r = after_ready(synchronised()["corner"], strategy).report
    assert r["durations_s"]["joint"] < 0.9 * r["durations_s"]["published"]


def test_arms_solved_apart_reach_the_bound_exactly() -> None:
    r = after_ready(synchronised()["corner"], "split").report
    assert r["solved"] == ["apart"]
    assert r["durations_s"]["joint"] == pytest.approx(r["jerk_limited_bound_s"], rel=1e-9)


def test_a_12_dof_transit_within_10_percent_of_the_bound() -> None:
    """The joint merge times a planned 12-DOF transit close to its jerk-limited bound: 8 %
    over on the quickest of four OMPL paths (2.36 s), which has sharper corners than the one
    path of a single query (3.35 s, 5 % over)."""
    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell), "split")
    r = c.add(ready()).report
    assert r["solved"] == ["together"]
    assert r["durations_s"]["joint"] <= r["durations_s"]["published"] * (1 + TIMING_SLACK)
    assert r["durations_s"]["joint"] <= 1.10 * r["jerk_limited_bound_s"]


def test_a_coupling_is_never_merged_the_published_way() -> None:
    world, cell, checker = cable_cell()
    c = Compiler(world, cell, checker, home(cell), "split", merge="published")
    for s in reference_segments():
        c.add(s)
    merges = {s.segment.label: s.report["merge"] for s in c.segments}
    assert merges["both down"] == "published"
    assert merges["lift together"] == "joint"  # a closed chain
    assert merges["left line"] == "none"  # one arm
