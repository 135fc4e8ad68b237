"""Segments to a Program: the executor's compiler.

For each segment, in order: the ``before`` gripper events (what each gripper holds is kept in
step with the collision checker), the arm paths solved into joint rows by the strategy
(:mod:`~cellengine.execute.strategies`), each part timed and merged onto one time axis
(:mod:`~cellengine.execute.merge`; async parts scheduled, :mod:`~cellengine.execute.schedule`),
each timed part through the gate before it is added, a kept distance checked along the
segment, then the ``after`` events at the segment's end.

A transit's goal configuration is chosen looking at the segments after it
(:mod:`~cellengine.execute.preview`), and a segment that cannot run sends the compiler back to
the latest transit for another goal (:mod:`~cellengine.execute.search`); when nothing gets
through, the compile stops with an InputError naming the step, the segment and why.

Compiling is pure: nothing moves, the caller's checker is not changed (the compiler attaches
held objects to its own), and the same inputs give the same program.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from itertools import chain
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from cellengine.arrays import Vec
from cellengine.execute import winding
from cellengine.execute.checks import gate, kept_distance, near_pairs
from cellengine.execute.failure import FailedAt
from cellengine.execute.following import required
from cellengine.execute.growing import UntilChange
from cellengine.execute.held import Held, Holding
from cellengine.execute.laid import Anchored, root, stretches
from cellengine.execute.merge import MERGES, Merge, Merged, merge_rows, on_one_axis
from cellengine.execute.preview import preview
from cellengine.execute.refused import Refused, in_plan_terms
from cellengine.execute.retime import standing
from cellengine.execute.schedule import SCHEDULE_DT, schedule
from cellengine.execute.search import add_all
from cellengine.execute.solve import Lookahead
from cellengine.execute.split import SPLIT_THRESHOLD
from cellengine.execute.strategies import STRATEGIES, Part, Strategy, solve_segment
from cellengine.info.cell import DEFAULT_CLEARANCE
from cellengine.motion.clearance import least
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.gate import SAMPLE_DT, GateReport
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import CollisionScene, Pair
from cellengine.motion.trajectory import Trajectory, concatenate
from cellengine.program import (
    Anchor,
    CompiledSegment,
    Program,
    Segment,
    TimedChange,
    TimedEvent,
    ToolChange,
)
from cellengine.world import World

# The cell with other tools on its arms (a tool change): its world, robot models (timed as
# the compiler's) and scene, given the tool of every arm.
Tooled = Callable[[Mapping[str, str | None]], tuple[World, CellModel, CollisionScene]]


@dataclass(frozen=True)
class Mark:
    """A compiler's state between two segments (q and the held-object state are never
    changed in place, so keeping them is enough; not the checker, which a search keeping a
    mark per segment would keep alive for every held state of the plan)."""

    q: Vec
    t: float
    segments: int
    events: int
    held: Held
    tools: tuple[tuple[str, str | None], ...]
    changes: int
    anchors: tuple[Anchored, ...]
    working: str | None


class Compiler:
    """Compiles segments one after another from ``q_start`` at t = 0 (``add``), keeping where
    the arms are, the time, and what each gripper holds; ``program()`` is the result so far."""

    def __init__(
        self,
        world: World,
        cell: CellModel,
        checker: CollisionChecker,
        q_start: ArrayLike,
        strategy: Strategy = "split",
        *,
        merge: Merge = "joint",
        split_threshold: float = SPLIT_THRESHOLD,
        clearance: float | None = None,
        tooled: Tooled | None = None,
    ) -> None:
        if strategy not in STRATEGIES:
            raise ValueError(f"unknown strategy '{strategy}'; known: {', '.join(STRATEGIES)}")
        if merge not in MERGES:
            raise ValueError(f"unknown merge '{merge}'; known: {', '.join(MERGES)}")
        q = np.array(q_start, dtype=float)
        if q.shape != (cell.nq,) or not np.isfinite(q).all():
            raise ValueError(f"q_start must be {cell.nq} finite values, got shape {q.shape}")
        self.cell = cell
        self.strategy: Strategy = strategy
        self.merge: Merge = merge
        self.split_threshold = split_threshold
        # m: the gate's and the async schedule's; cell.yaml's unless given
        self.clearance = world.cell.clearance if clearance is None else clearance
        # checkers of its own: attaching held objects must not change the caller's
        self.holding = Holding(world, checker.scene)
        self.q = q
        self.t = 0.0
        self.segments: list[CompiledSegment] = []
        self.events: list[TimedEvent] = []
        # the tool each arm carries; a change switches the cell model and the scene to those
        # of the new tools (``tooled``), each assignment's built once and kept with its holding
        self.tooled = tooled
        self.tools = _key(world.tools)
        self.start_tools = self.tools
        self.changes: list[TimedChange] = []
        self.tooling: dict[tuple[tuple[str, str | None], ...], tuple[CellModel, Holding]] = {
            self.tools: (cell, self.holding)
        }
        # where cables are fixed so far, and the harness (or cable) the hands held last: the
        # cables laid of any other are obstacles (execute/laid.py)
        self.anchors: tuple[Anchored, ...] = ()
        self.working: str | None = None

    def add(
        self, segment: Segment, following: Sequence[Segment] = (), choice: int = 0
    ) -> CompiledSegment:
        """Compile one segment after those already added; InputError if it cannot run (the
        compiler is then as it was before: a caller may try another segment instead).
        ``following``: the segments after it, if known: a transit then reaches its goal in a
        configuration from which the arm's next Cartesian path can be followed. ``choice``:
        which goal configuration a transit takes (0: the first that works)."""
        mark = self.mark()
        try:
            compiled = self._compile(segment, following, choice)
        except Refused as e:
            self.restore(mark)
            if e.at is None:  # nothing more known: the arms where the segment began
                e.at = FailedAt("segment", np.array(self.q))
            raise in_plan_terms(segment, e, self.program()) from None
        self.segments.append(compiled)
        self.q = np.array(compiled.trajectory.q[-1])
        self.t = compiled.trajectory.end_time
        return compiled

    def add_all(
        self, segments: Sequence[Segment], before_each: Callable[[Segment], None] | None = None
    ) -> Program:
        """Add ``segments`` in order, each looking ahead to those after it, coming back to an
        earlier transit when a later segment cannot run (search.py); the program. Prefer it to
        calling :meth:`add` in a loop, which can neither look ahead nor come back.
        ``before_each(segment)`` is called before each segment is compiled (progress)."""
        add_all(self, list(segments), before_each)
        return self.program()

    def mark(self) -> Mark:
        """Where the compiler is: :meth:`restore` comes back here."""
        return Mark(
            self.q,
            self.t,
            len(self.segments),
            len(self.events),
            self.holding.state,
            self.tools,
            len(self.changes),
            self.anchors,
            self.working,
        )

    def restore(self, mark: Mark) -> None:
        if mark.segments > len(self.segments) or mark.events > len(self.events):
            # a mark taken on an attempt given up: restoring it would join segments that do
            # not meet
            raise ValueError("restore: the mark is ahead of what is compiled")
        self.q, self.t = mark.q, mark.t
        del self.segments[mark.segments :]
        del self.events[mark.events :]
        del self.changes[mark.changes :]
        self.tools = mark.tools
        self.cell, self.holding = self.tooling[mark.tools]
        self.holding.restore(mark.held)
        self.anchors, self.working = mark.anchors, mark.working

    @property
    def transit_clearance(self) -> float:
        """What transits keep between the arms and from the environment (m): the cell's
        clearance, and at least the default. A cell lowers its clearance so that its skills'
        moves along guides and combs get past the gate; a transit is a move through free
        space, with no reason to come closer (as the async schedule's arms moving on their
        own), and its start and goal lower it where they must (motion.margins)."""
        return max(self.clearance, DEFAULT_CLEARANCE)

    @property
    def checker(self) -> CollisionChecker:
        """The collision checker of the cell with what the grippers hold now."""
        return self.holding.checker

    def program(self) -> Program:
        return Program(
            self.cell.joint_names,
            tuple(self.segments),
            tuple(self.events),
            changes=tuple(self.changes),
            tools=MappingProxyType(dict(self.start_tools)),
        )

    def _lay(self, segment: Segment) -> None:
        """The cables the segment anchors, and the one it holds, from its end on."""
        world = self.holding.world
        anchors = [(a.object, a.point) for a in segment.annotations if isinstance(a, Anchor)]
        held = [e.holds for e in (*segment.before, *segment.after) if e.holds is not None]
        if not anchors and not held:
            return
        self.anchors += tuple(anchors)
        if held:
            self.working = root(world, held[-1])
        self.holding.lay(stretches(world, self.anchors, self.working))

    def _change(self, changes: Iterable[ToolChange], t: float) -> None:
        """Each arm of ``changes`` carries its new tool from ``t``: the cell model and the
        scene become those of the new tools, with what the grippers hold carried over."""
        for c in changes:
            tools = dict(self.tools)
            if c.arm not in tools:
                raise ValueError(f"a tool change of unknown arm '{c.arm}'")
            held = self.holding.by_arm.get(c.arm)
            if held is not None:
                raise Refused(f"the {c.arm} arm changes its tool while it holds '{held}'")
            if self.tooled is None:
                raise ValueError("a tool change needs a compiler given `tooled`")
            was, tools[c.arm] = tools[c.arm], c.tool
            key = _key(tools)
            if key not in self.tooling:
                world, cell, scene = self.tooled(tools)
                self.tooling[key] = (cell, Holding(world, scene))
            state = self.holding.state
            self.cell, self.holding = self.tooling[key]
            jaw = {a: v for a, v in state.jaw.items() if a != c.arm}  # the new tool's widest
            self.holding.restore(replace(state, jaw=jaw))
            self.tools = key
            self.changes.append(TimedChange(t, c.arm, c.tool, was))

    # ------------------------------------------------------------------------------ one segment

    def _compile(
        self, segment: Segment, following: Sequence[Segment], choice: int
    ) -> CompiledSegment:
        started = time.perf_counter()
        t0 = self.t
        following = () if segment.changes else UntilChange(following)
        self._events(segment.before, t0, self.q)
        self.holding.touch(segment.contacts)
        has_transit = any(p.kind == "transit" for p in segment.paths)
        accept = preview(self.cell, self.holding, following) if has_transit else None
        ahead = None
        if has_transit:
            ahead = {
                p.arm: Lookahead(
                    winding.ahead(following, p.arm), required(chain((segment,), following), p.arm)
                )
                for p in segment.paths
            }
        self._check_branches(segment)
        parts = solve_segment(
            self.cell,
            self.checker,
            segment,
            self.q,
            self.strategy,
            self.split_threshold,
            accept,
            choice,
            self.transit_clearance,
            ahead,
        )
        return self._assembled(segment, parts, t0, transit_choice=choice, started=started)

    def add_parts(self, segment: Segment, parts: Sequence[Part]) -> CompiledSegment:
        """Add a segment whose joint rows are solved already (a return home planned in
        joint space): timed, merged and gated as any other; InputError if it cannot run."""
        mark = self.mark()
        try:
            started = time.perf_counter()
            self._events(segment.before, self.t, self.q)
            self.holding.touch(segment.contacts)
            compiled = self._assembled(segment, parts, self.t, transit_choice=0, started=started)
        except Refused as e:
            self.restore(mark)
            raise in_plan_terms(segment, e) from None
        self.segments.append(compiled)
        self.q = np.array(compiled.trajectory.q[-1])
        self.t = compiled.trajectory.end_time
        return compiled

    def _assembled(
        self,
        segment: Segment,
        parts: Sequence[Part],
        t0: float,
        transit_choice: int,
        started: float,
    ) -> CompiledSegment:
        """The segment's solved ``parts`` timed, merged and through the gate from ``t0`` (its
        ``before`` events done), with its ``after`` events, as a compiled segment."""
        merge = self._merge_for(segment)
        near = self._near(segment)
        pieces: list[Trajectory] = []
        figures: list[tuple[Part, Merged, GateReport, dict[str, float]]] = []
        t, q = t0, self.q
        for part in parts:
            # an async transit planned as one (strategies._async_transit): one time law
            joint = self.strategy == "async" and part.solved == "together"
            merged = merge_rows(self.cell, q, part.rows, part.coupled, "joint" if joint else merge)
            traj, report, starts = self._timed(part, merged, t, q, near)
            pieces.append(traj)
            figures.append((part, merged, report, starts))
            t, q = traj.end_time, np.array(traj.q[-1])
        if segment.hold > 0.0:  # the arms stand still where the motion ended
            pieces.append(standing(q, self.cell.joint_names, t, segment.hold))
        trajectory = concatenate(pieces) if len(pieces) > 1 else pieces[0]
        kept = None
        if segment.keep_distance is not None:
            kept = kept_distance(trajectory, self.cell, segment.keep_distance)
        self._events(segment.after, trajectory.end_time, np.asarray(trajectory.q[-1]))
        self.holding.touch(())
        self._lay(segment)
        self._change(segment.changes, trajectory.end_time)
        summary = _report(
            segment, self.strategy, _merge_name(list(parts), merge, self.strategy), figures, kept
        )
        summary["transit_choice"] = transit_choice
        summary["planning_time_s"] = time.perf_counter() - started
        summary["start_s"] = t0
        summary["duration_s"] = trajectory.end_time - t0
        return CompiledSegment(segment, self.strategy, trajectory, summary)

    def _near(self, segment: Segment) -> frozenset[Pair]:
        return near_pairs(self.cell, self.checker.scene, segment)

    def _check_branches(self, segment: Segment) -> None:
        """Refuse an arm (following a Cartesian path or standing) on an IK branch the segment
        does not require of it (Segment.branches), and two arms on a pair of branches it does
        not pair (Segment.paired): the skill's checks of its poses did not look at them, and
        the transit that chose them did not look ahead at them."""
        moved = {p.arm for p in segment.paths if p.kind == "transit"}
        for arm, on in segment.branches:  # an arm that stands too: the skill looked at it
            ik = arm_ik(self.cell.arms[arm])
            if arm in moved or ik.closed_form is None:
                continue
            branch = ik.branch(self.q[self.cell.slices[arm]])
            if branch not in on:
                raise Refused(
                    f"the {arm} arm is on IK branch {branch}; the skill checked this "
                    f"segment's poses on branches {sorted(on)} only",
                    configuration=True,
                )
        for a, b, pairs in segment.paired:
            iks = [arm_ik(self.cell.arms[arm]) for arm in (a, b)]
            if a in moved or b in moved or any(ik.closed_form is None for ik in iks):
                continue
            i, j = (
                ik.branch(self.q[self.cell.slices[x]]) for ik, x in zip(iks, (a, b), strict=True)
            )
            if (i, j) not in pairs:
                raise Refused(
                    f"the {a} and {b} arms are on IK branches {i} and {j}; the skill "
                    f"checked this segment's poses with them on {sorted(pairs)} only",
                    configuration=True,
                )

    def _merge_for(self, segment: Segment) -> Merge:
        """A coupling (closed chain, kept distance) needs one time law for both arms: the
        published merge, which retimes one arm point by point, would break it. So does a
        transit of two arms planned as one (all but async): the planner proved the pair free
        moving together, and a transit keeping only the clearance between them collides when
        one arm runs ahead of the other."""
        if segment.closed_chain is not None or segment.keep_distance is not None:
            return "joint"
        arms = {p.arm for p in segment.paths}
        both_transit = len(arms) > 1 and all(p.kind == "transit" for p in segment.paths)
        if both_transit and self.strategy != "async":
            return "joint"
        return self.merge

    def _events(self, events: Iterable[Any], t: float, q: Vec) -> None:
        for e in events:
            arm = self.cell.arms[e.arm]
            T_cell_tcp = arm.fk(self.cell.split(q)[e.arm])
            try:
                self.holding.set(e.arm, e.holds, T_cell_tcp, e.mode)
            except (ValueError, KeyError) as err:
                raise Refused(
                    f"the {e.arm} gripper cannot hold '{e.holds}': {err}",
                    at=FailedAt("segment", np.array(q)),
                ) from None
            self.events.append(TimedEvent(t, e))

    def _timed(
        self, part: Part, merged: Merged, t: float, q: Vec, near: frozenset[Pair]
    ) -> tuple[Trajectory, GateReport, dict[str, float]]:
        """The part's trajectory at its place on the program's time axis, through the gate,
        and each arm's start in it. Async parts of several arms are scheduled; when the gate's
        1 ms samples find a collision the scheduler's coarser ones missed, they are scheduled
        again at the gate's resolution."""
        if self.strategy != "async" or part.solved != "apart" or len(merged.alone) < 2:
            traj = merged.trajectory.shifted(t)
            return traj, gate(traj, self.cell, self.checker, self.clearance, near), {}
        refused = Refused("unreachable")
        for dt in (SCHEDULE_DT, SAMPLE_DT):
            # two arms moving on their own keep at least the default apart, even in a cell
            # that lowers its clearance to get its plans past the gate
            margin = max(self.clearance, DEFAULT_CLEARANCE)
            starts = schedule(self.cell, q, merged.alone, self.checker, dt=dt, clearance=margin)
            traj = on_one_axis(self.cell, q, merged.alone, starts).shifted(t)
            try:
                return traj, gate(traj, self.cell, self.checker, self.clearance, near), starts
            except Refused as e:
                refused = e
        raise refused


def _key(tools: Mapping[str, str | None]) -> tuple[tuple[str, str | None], ...]:
    return tuple(sorted(tools.items()))


def compile_segments(
    world: World,
    cell: CellModel,
    checker: CollisionChecker,
    segments: Iterable[Segment],
    q_start: ArrayLike,
    strategy: Strategy = "split",
    *,
    merge: Merge = "joint",
    split_threshold: float = SPLIT_THRESHOLD,
) -> Program:
    """The program of ``segments`` from the cell configuration ``q_start`` (see the module
    notes). ``merge`` chooses which merge times two-arm parts (both are in the report)."""
    compiler = Compiler(
        world,
        cell,
        checker,
        q_start,
        strategy,
        merge=merge,
        split_threshold=split_threshold,
    )
    return compiler.add_all(list(segments))


# ------------------------------------------------------------------------------ report


def _merge_name(parts: list[Part], merge: Merge, strategy: Strategy) -> str:
    if not any(len(p.rows) > 1 for p in parts):
        return "none"  # one arm or none: nothing to merge
    if strategy == "async" and any(p.solved == "apart" for p in parts):
        return "async"
    if strategy == "async" and all(p.solved == "together" for p in parts):
        return "joint"  # solved on one grid (a closed chain, a transit planned as one)
    return merge


def _report(
    segment: Segment,
    strategy: Strategy,
    merge: str,
    figures: list[tuple[Part, Merged, GateReport, dict[str, float]]],
    kept: Any,
) -> dict[str, Any]:
    """What report.json says of a segment: plain JSON values."""
    fraction: dict[str, float] = {}
    for part, *_ in figures:
        for arm, f in part.fraction.items():
            fraction[arm] = min(f, fraction.get(arm, 1.0))
    distances = [r.min_arm_distance for _, _, r, _ in figures if r.min_arm_distance is not None]
    closest = min(
        (r for _, _, r, _ in figures if r.min_arm_distance is not None),
        key=lambda r: r.min_arm_distance or 0.0,
        default=None,
    )
    return {
        "step": segment.step,
        "label": segment.label,
        "strategy": strategy,
        "solved": sorted({p.solved for p, *_ in figures}),
        "merge": merge,
        "parts": len(figures),
        "split_at": [dict(p.split_at) for p, *_ in figures if p.split_at],
        "delays_s": [s for *_, s in figures if s],
        "fraction": fraction,
        "durations_s": {m: sum(f.durations[m] for _, f, _, _ in figures) for m in MERGES},
        "time_optimal_bound_s": sum(f.bound for _, f, _, _ in figures),
        "jerk_limited_bound_s": sum(f.bound_jerk for _, f, _, _ in figures),
        "min_arm_distance_m": min(distances) if distances else None,
        "clearance": least([r.clearance for _, _, r, _ in figures if r.clearance]).figures(),
        "closest_pair": list(closest.closest_pair or ()) if closest is not None else None,
        "near": [list(n) for n in segment.near],
        "keep_distance": None
        if kept is None
        else {
            "arms": list(segment.keep_distance or ()),
            "distance_m": kept.distance,
            "deviation_m": kept.deviation,
        },
        "checks_passed": True,  # a check that fails stops the compile
        "checks": {
            "cartesian_fraction": True,
            "gate": True,
            "gate_samples": sum(r.samples for _, _, r, _ in figures),
            "keep_distance": None if kept is None else True,
        },
    }
