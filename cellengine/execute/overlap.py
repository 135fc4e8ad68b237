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
from cellengine.execute.retime import timed
from cellengine.execute.streams import SCHEDULE_DT, Piece, Streams
from cellengine.motion.gate import SAMPLE_DT
from cellengine.motion.robot import CellModel
from cellengine.motion.scene import CollisionScene
from cellengine.motion.speed import tcp_limit
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
    events: list[TimedEvent] = []
    out: list[CompiledSegment] = []
    for piece in pieces:
        starting = [s for s in piece.slots if abs(s.start - piece.lo) < 1e-9]
        ending = [s for s in scheduled if abs(s.end - piece.hi) < 1e-9]
        before = tuple(e for s in starting for e in compiled[s.index].segment.before)
        after = tuple(e for s in ending for e in compiled[s.index].segment.after)
        events += [TimedEvent(piece.lo, e) for e in before]
        events += [TimedEvent(piece.hi, e) for e in after]
        notes = tuple(a for s in ending for a in compiled[s.index].segment.annotations)
        first = compiled[piece.slots[0].index].segment if piece.slots else None
        segment = Segment(
            step=first.step if first is not None else _step_at(scheduled, piece.lo),
            # one segment alone in the piece: its couplings (the report shows them)
            closed_chain=first.closed_chain if len(piece.slots) == 1 and first else None,
            keep_distance=first.keep_distance if len(piece.slots) == 1 and first else None,
            label=" + ".join(compiled[s.index].segment.label for s in piece.slots) or "wait",
            before=before,
            after=after,
            annotations=tuple(a for a in notes if isinstance(a, Measure | Anchor)),
            # what the segments ending with it promise, and which segments run in it
            facts={
                **{k: v for s in ending for k, v in compiled[s.index].segment.facts.items()},
                "segments": [s.index for s in piece.slots],
            },
        )
        out.append(
            CompiledSegment(
                segment,
                compiled[0].strategy,
                piece.trajectory,
                _report(piece, compiled, starting),
            )
        )
    names = compiled[0].trajectory.joint_names
    return Program(names, tuple(out), tuple(events), tuple(scheduled), done)


def _step_at(scheduled: Sequence[Scheduled], t: float) -> int:
    return next((s.step for s in scheduled if s.start >= t - 1e-9), scheduled[-1].step)


def _report(
    piece: Piece, compiled: Sequence[CompiledSegment], starting: Sequence[Any]
) -> dict[str, Any]:
    """What report.json says of a piece: the gate's figures of it, and the planning time
    of the segments starting in it (each counted once)."""
    r = piece.report
    moving = {p.arm: p.kind for s in piece.slots for p in compiled[s.index].segment.paths}
    return {
        "arms": moving,
        "segments": [s.index for s in piece.slots],
        "planning_time_s": sum(
            float(compiled[s.index].report.get("planning_time_s", 0.0)) for s in starting
        ),
        "start_s": piece.lo,
        "duration_s": piece.hi - piece.lo,
        "min_arm_distance_m": r.min_arm_distance,
        "closest_pair": list(r.closest_pair or ()) or None,
        "clearance": r.clearance.figures() if r.clearance is not None else None,
        "checks_passed": True,  # a piece the gate refuses is not in the program
        "checks": {"gate": True, "gate_samples": r.samples},
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
