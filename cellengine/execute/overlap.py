"""A program compiled one segment after another, its arms' streams run at once: the
schedule (streams.py), then the pieces a driver plays, each through the gate at 1 ms.

Placing is checked at 10 ms; when the gate's 1 ms samples refuse a piece, the segments are
placed again checked at 1 ms. When even that is refused (it should not be), the program
runs as compiled, and its report says why.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from cellengine.concurrency import Overlap
from cellengine.execute.held import Holding
from cellengine.execute.refused import Refused
from cellengine.execute.retime import still, timed
from cellengine.execute.streams import SAME, SCHEDULE_DT, Piece, Streams
from cellengine.execute.timeline_arms import Slot
from cellengine.motion.clearance import least
from cellengine.motion.gate import SAMPLE_DT
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import CollisionScene
from cellengine.motion.speed import tcp_limit
from cellengine.motion.trajectory import joined
from cellengine.program import (
    Anchor,
    CompiledSegment,
    Measure,
    Program,
    Scheduled,
    Segment,
    TimedEvent,
)
from cellengine.world import World

KEPT_SCENES = 32  # the held states' checkers kept while replaying the streams
REST_DT = 0.001  # s: where a stopped segment's arms are on its path, found this finely


def overlapped(
    program: Program,
    rules: Overlap,
    world: World,
    cell: CellModel,
    scene: CollisionScene,
    clearance: float,
) -> tuple[Program, str | None]:
    """The program with its arms' streams at once, or as it is and why not."""
    if not program.segments:
        return program, None
    q0 = np.array(program.segments[0].trajectory.q[0])
    try:
        out = _placed(program.segments, rules, world, cell, scene, clearance, q0)
    except Refused as e:
        return program, f"the pieces of both streams fail the gate: {e}"
    return out, None


def resumed(
    program: Program,
    rules: Overlap,
    world: World,
    cell: CellModel,
    scene: CollisionScene,
    clearance: float,
    done: frozenset[int],
    running: frozenset[int],
    q: np.ndarray,
) -> Program:
    """What is left of an overlapped ``program`` (as compiled) once the segments ``done``
    (indices of its ``streams``) are finished and those ``running`` were stopped part way,
    the arms at ``q`` (a piece's end, where a recovery move brings them back to): each
    running segment goes on from there along its path, timed again from rest (its
    ``before`` events were done), the grippers as what was done left them, the rest placed
    again. Refused when its pieces fail the gate."""
    every = {s.index: s for s in program.streams}
    segments = [every[i].compiled for i in range(len(every))]
    q0 = np.array(q, dtype=float)
    holding = Holding(world, scene, keep=KEPT_SCENES)
    events = []
    for i in done | running:
        s, traj = every[i], every[i].compiled.trajectory
        events += [(s.start, i, 0, e, traj.q[0]) for e in s.segment.before]
        if i in done:
            events += [(s.end, i, 1, e, traj.q[-1]) for e in s.segment.after]
    for _, _, _, e, qe in sorted(events, key=lambda x: (round(x[0], 9), x[1], x[2])):
        holding.set(e.arm, e.holds, cell.arms[e.arm].fk(qe[cell.slices[e.arm]]), e.mode)
    for i in running:
        segments[i] = _rest_of(segments[i], every[i].arms, q0, cell)
    return _placed(segments, rules, world, cell, scene, clearance, q0, holding, done)


def _rest_of(
    cs: CompiledSegment, arms: Sequence[str], q: np.ndarray, cell: CellModel
) -> CompiledSegment:
    """A segment stopped with its arms at ``q``: the rest of its path from the point on it
    nearest ``q``, timed from rest, without its ``before`` events (they were done)."""
    traj = cs.trajectory
    cols = np.concatenate([np.arange(cell.nq)[cell.slices[a]] for a in arms])
    n = max(2, int(np.ceil(traj.duration / REST_DT)) + 1)
    t = np.linspace(traj.start_time, traj.end_time, n)
    near = int(np.argmin(np.linalg.norm(traj.sample(t)[0][:, cols] - q[cols], axis=1)))
    rows = np.vstack([q, traj.q[traj.t > t[near] + 1e-9]])
    others = np.setdiff1d(np.arange(cell.nq), cols)
    rows[:, others] = q[others]  # the other arms' columns: as they stand (not used)
    rest = timed(rows, cell.timing_limits(), cell.joint_names, tcp_limit(cell))
    segment = replace(cs.segment, before=())
    return CompiledSegment(segment, cs.strategy, rest, {**cs.report, "resumed": True})


def _placed(
    segments: Sequence[CompiledSegment],
    rules: Overlap,
    world: World,
    cell: CellModel,
    scene: CollisionScene,
    clearance: float,
    q0: np.ndarray,
    holding: Holding | None = None,
    done: frozenset[int] = frozenset(),
) -> Program:
    """The segments placed (but ``done``) and cut into pieces: Refused when even placed
    checking every 1 ms, a piece fails the gate."""
    start = None if holding is None else holding.state
    refused = Refused("no segments")
    for dt in (SCHEDULE_DT, SAMPLE_DT):
        hold = holding or Holding(world, scene, keep=KEPT_SCENES)
        if start is not None:
            hold.restore(start)
        streams = Streams(segments, rules, cell, hold, q0, clearance)
        scheduled = streams.place_all(dt, done)
        try:
            pieces = streams.pieces(0.0, streams.timeline.makespan)
        except Refused as e:
            refused = e
            continue
        return _program(segments, scheduled, pieces, done)
    raise refused


def _program(
    compiled: Sequence[CompiledSegment],
    scheduled: Sequence[Scheduled],
    pieces: Sequence[Piece],
    done: frozenset[int],
) -> Program:
    """The pieces as what a driver plays: those joined by a segment running across their
    boundary as one (a driver that stops the arms between the segments it is sent must not
    stop one mid-motion), each with the events, notes and facts of the segments in it."""
    events: list[TimedEvent] = []
    out: list[CompiledSegment] = []
    at_start = [x for x in scheduled if x.index not in done and x.end <= SAME]
    if at_start:
        out.append(_standing(compiled, at_start))
        events += [TimedEvent(0.0, e) for x in at_start for e in compiled[x.index].segment.after]
    for window in _windows(pieces):
        lo, hi = window[0].lo, window[-1].hi
        slots = sorted({s for p in window for s in p.slots}, key=lambda s: s.index)
        starting = [s for s in slots if lo - SAME <= s.start < hi - SAME]
        ending = [e for e in scheduled if lo + SAME < e.end <= hi + SAME]
        for s in starting:
            events += [TimedEvent(s.start, e) for e in compiled[s.index].segment.before]
        for x in ending:
            events += [TimedEvent(x.end, e) for e in compiled[x.index].segment.after]
        first = [compiled[s.index].segment for s in starting if s.start <= lo + SAME]
        last = [compiled[x.index].segment for x in ending if x.end >= hi - SAME]
        segs = [compiled[s.index].segment for s in slots]
        notes = [a for x in ending for a in compiled[x.index].segment.annotations]
        one = segs[0] if len(segs) == 1 else None
        segment = Segment(
            step=segs[0].step if segs else _step_at(scheduled, lo),
            label=" + ".join(dict.fromkeys(seg.label for seg in segs)) or "wait",
            # one segment alone in it: its couplings (the report shows them)
            closed_chain=one.closed_chain if one else None,
            keep_distance=one.keep_distance if one else None,
            before=tuple(e for seg in first for e in seg.before),
            after=tuple(e for seg in last for e in seg.after),
            annotations=tuple(a for a in notes if isinstance(a, Measure | Anchor)),
            # what the segments ending in it promise, and which segments run in it
            facts={
                **{k: v for x in ending for k, v in compiled[x.index].segment.facts.items()},
                "segments": [s.index for s in slots],
            },
        )
        trajectory = joined([p.trajectory for p in window])
        report = _report(window, compiled, slots, starting)
        out.append(CompiledSegment(segment, compiled[0].strategy, trajectory, report))
    names = compiled[0].trajectory.joint_names
    events.sort(key=lambda e: e.time)
    return Program(names, tuple(out), tuple(events), tuple(scheduled), done)


def _standing(
    compiled: Sequence[CompiledSegment], at_start: Sequence[Scheduled]
) -> CompiledSegment:
    """The segments with nothing left to move at the program's start (a resumed run's
    segment stopped at its end, its weighing or last gripper event not done): no piece has
    them, so they are played first, as standing still, with their events and readings."""
    segs = [compiled[x.index].segment for x in at_start]
    first = compiled[at_start[0].index]
    segment = Segment(
        step=segs[0].step,
        label=" + ".join(dict.fromkeys(seg.label for seg in segs)),
        after=tuple(e for seg in segs for e in seg.after),
        annotations=tuple(
            a for seg in segs for a in seg.annotations if isinstance(a, Measure | Anchor)
        ),
        facts={"segments": [x.index for x in at_start]},
    )
    report = {
        "arms": {p.arm: p.kind for seg in segs for p in seg.paths},
        "segments": [x.index for x in at_start],
        "pieces": 0,
        "planning_time_s": 0.0,
        "start_s": 0.0,
        "duration_s": 0.0,
        "min_arm_distance_m": None,
        "closest_pair": None,
        "clearance": None,
        "checks_passed": True,
        "checks": {"gate": True, "gate_samples": 0},
    }
    q = first.trajectory.q[0]
    return CompiledSegment(segment, first.strategy, still(q, first.trajectory.joint_names), report)


def _windows(pieces: Sequence[Piece]) -> list[list[Piece]]:
    """The pieces in runs joined by a segment running across their boundary."""
    out: list[list[Piece]] = []
    for piece in pieces:
        if out and set(out[-1][-1].slots) & set(piece.slots):
            out[-1].append(piece)
        else:
            out.append([piece])
    return out


def _step_at(scheduled: Sequence[Scheduled], t: float) -> int:
    return next((s.step for s in scheduled if s.start >= t - SAME), scheduled[-1].step)


def _report(
    window: Sequence[Piece],
    compiled: Sequence[CompiledSegment],
    slots: Sequence[Slot],
    starting: Sequence[Slot],
) -> dict[str, Any]:
    """What report.json says of what is played as one: the gate's figures of its pieces,
    and the planning time of the segments starting in it (each counted once)."""
    reports = [p.report for p in window]
    distances = [r for r in reports if r.min_arm_distance is not None]
    closest = min(distances, key=lambda r: r.min_arm_distance or 0.0, default=None)
    clearances = [r.clearance for r in reports if r.clearance is not None]
    return {
        "arms": {p.arm: p.kind for s in slots for p in compiled[s.index].segment.paths},
        "segments": [s.index for s in slots],
        "pieces": len(window),
        "planning_time_s": sum(
            float(compiled[s.index].report.get("planning_time_s", 0.0)) for s in starting
        ),
        "start_s": window[0].lo,
        "duration_s": window[-1].hi - window[0].lo,
        "min_arm_distance_m": None if closest is None else closest.min_arm_distance,
        "closest_pair": None if closest is None else list(closest.closest_pair or ()) or None,
        "clearance": least(clearances).figures() if clearances else None,
        "checks_passed": True,  # a piece the gate refuses is not in the program
        "checks": {"gate": True, "gate_samples": sum(r.samples for r in reports)},
    }


def streams_json(program: Program, one_after_another: float, refused: str | None) -> dict[str, Any]:
    """report.json's ``streams``: each arm's segments where they were placed, what each
    waited for, and the program's length against its segments one after another."""
    lanes: dict[str, list[dict[str, Any]]] = {}
    for s in program.streams:
        entry = {
            "segment": s.index,
            "label": s.label,
            "step": s.step,
            "arms": list(s.arms),
            "start": round(s.start, 6),
            "end": round(s.end, 6),
            "wait_s": round(s.wait, 6),
            "waited_for": s.why,
        }
        for arm in s.arms:
            lanes.setdefault(arm, []).append(entry)
    return {
        "at_once": bool(program.streams),
        "duration_s": program.duration,
        "one_after_another_s": one_after_another,
        "refused": refused,
        "lanes": lanes,
        "waits": [
            {"segment": s.index, "label": s.label, "wait_s": round(s.wait, 6), "why": s.why}
            for s in program.streams
            if s.why is not None
        ],
    }
