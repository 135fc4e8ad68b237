"""report.json's content: per step and per segment, what was planned and how it went.

Keys carry their unit (``_s``, ``_m``), as the executor's do. Per segment: ``index``,
``step``, ``label``, ``strategy``, ``merge``, ``start_s``, ``end_s``, ``duration_s``, ``arms``
({arm: cartesian | transit}), ``cartesian_fraction`` ({arm: fraction or None}),
``planning_time_s``, ``min_arm_distance_m`` and ``closest_pair``, ``distance_source``
(executor | computed), ``checks_passed`` (True, False, or None: not reported), the gripper
events ``before`` and ``after``, ``closed_chain``, ``keep_distance``, ``facts``.

Every key of :attr:`CompiledSegment.report` passes through unchanged at the segment's level
(the segment's own description fills only keys the executor did not give). The figures above
are read from it, first key found wins:

- ``cartesian_fraction`` or ``fraction``: a number (every Cartesian arm) or {arm: number};
- ``planning_time_s`` or ``planning_time``;
- ``min_arm_distance_m``, ``min_arm_distance`` or ``min_distance``; ``closest_pair`` or ``pair``;
- ``checks_passed`` (bool), or ``checks``: a bool, {name: bool} (non-bool entries such as
  sample counts ignored), or a list of violations (empty: passed);
- ``gate``: a :class:`~cellengine.motion.gate.GateReport` (``ok``, ``min_arm_distance``,
  ``closest_pair``) when the keys above are absent.

Without a reported distance, and given the cell, the distance between the arms' links is
measured every DISTANCE_DT s along the segment (``distance_source``: ``computed``).
Per step: the same figures over its segments (planning times summed, the smallest distance,
checks passed when all passed). ``totals``: ``cycle_time_s``, ``cycle_time_by_merge_s``
(the cycle had every segment used each merge of its ``durations_s``), counts,
``planning_time_s``, ``min_arm_distance_m``, ``closest_pair``, ``checks_passed``, and
``clearance``: of the segments' ``clearance`` (the executor's: ``{arms, environment}``, each
``{distance_m, pair, time_s}``), the least of each kind with its segment's index and label.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from cellengine.motion.robot import CellModel
from cellengine.program import CompiledSegment, GripperEvent, Program, TimedEvent
from cellengine.report.distance import ArmDistance
from cellengine.report.jsonable import jsonable
from cellengine.report.sampling import joint_order
from cellengine.report.tools import tool_timeline

REPORT_FORMAT = "cellengine.report/1"
DISTANCE_DT = 0.01  # s between states measured for a segment's distance between the arms
FRACTION_KEYS = ("cartesian_fraction", "fraction")
PLANNING_KEYS = ("planning_time_s", "planning_time")
DISTANCE_KEYS = ("min_arm_distance_m", "min_arm_distance", "min_distance")
PAIR_KEYS = ("closest_pair", "pair")


def report_data(
    program: Program,
    cell: CellModel | None = None,
    *,
    step_labels: Mapping[int, str] | None = None,
    extra: Mapping[str, Any] | None = None,
) -> dict[str, Any]:
    """report.json's body. ``step_labels`` names plan steps (else each step is named by its
    first segment's label up to ':'); ``extra`` adds top-level keys (it may not replace one)."""
    distance = _distance_fn(program, cell)
    segments = [_segment(i, cs, distance) for i, cs in enumerate(program.segments)]
    steps = _steps(segments, step_names(program, step_labels))
    out: dict[str, Any] = {
        "format": REPORT_FORMAT,
        "joint_names": list(program.joint_names),
        "arms": _arms(program, cell),
        "totals": _totals(program, segments, steps),
        "steps": steps,
        "segments": segments,
        "events": [event_entry(e) for e in program.events],
    }
    if program.changes:  # the tool each arm carries at the start, and every change
        out["tools"] = tool_timeline(program)
    for key, value in (extra or {}).items():
        if key in out:
            raise ValueError(f"extra key '{key}' would replace the report's own")
        out[str(key)] = jsonable(value)
    return out


def event_entry(e: TimedEvent) -> dict[str, Any]:
    return {"time": float(e.time), **_gripper(e.event)}


def step_label(labels: Sequence[str]) -> str:
    """A step's name from its segments' labels: the words before ':' that all of them begin
    with ('RouteCable guide2: lift', 'RouteCable guide2: insert' -> 'RouteCable guide2'), else
    the first label's first word (the skill: 'RouteCable guide1: ...', 'RouteCable guide2: ...',
    'cable1: release' -> 'RouteCable')."""
    heads = [label.split(":", 1)[0].split() for label in labels]
    if not heads or not heads[0]:
        return labels[0] if labels else ""
    common: list[str] = []
    for words in zip(*heads, strict=False):  # up to the shortest
        if any(w != words[0] for w in words):
            break
        common.append(words[0])
    return " ".join(common) or heads[0][0]


def step_names(program: Program, given: Mapping[int, str] | None = None) -> dict[int, str]:
    """Each plan step's name: ``given`` (from the plan), else :func:`step_label`."""
    labels: dict[int, list[str]] = {}
    for cs in program.segments:
        labels.setdefault(int(cs.segment.step), []).append(cs.segment.label)
    given = given or {}
    return {step: given.get(step) or step_label(parts) for step, parts in labels.items()}


# ---------------------------------------------------------------------------------- segments


class _Distance:
    """The distance between the arms along a segment's trajectory, in the cell's joints."""

    def __init__(self, program: Program, cell: CellModel) -> None:
        self.measure = ArmDistance(cell)
        self.order = joint_order(program, cell.joint_names)

    def __call__(self, cs: CompiledSegment) -> tuple[float, tuple[str, str]] | None:
        traj = cs.trajectory
        times = np.append(np.arange(traj.start_time, traj.end_time, DISTANCE_DT), traj.end_time)
        q, _, _ = traj.sample(times)
        return self.measure.minimum(q[:, self.order])


def _distance_fn(program: Program, cell: CellModel | None) -> _Distance | None:
    if cell is None or len(cell.arms) < 2 or not program.segments:
        return None
    return _Distance(program, cell)


def _segment(i: int, cs: CompiledSegment, distance: _Distance | None) -> dict[str, Any]:
    seg, r, traj = cs.segment, cs.report, cs.trajectory
    gate = r.get("gate")
    passthrough = jsonable(r)
    out: dict[str, Any] = dict(passthrough) if isinstance(passthrough, dict) else {}
    d, pair, source = _reported_distance(r, gate)
    if d is None and distance is not None:
        found = distance(cs)
        if found is not None:
            d, pair, source = found[0], found[1], "computed"
    out.update(
        {
            "index": i,
            "strategy": cs.strategy,
            "merge": jsonable(r.get("merge")),
            "start_s": traj.start_time,
            "end_s": traj.end_time,
            "duration_s": traj.duration,
            "cartesian_fraction": _fractions(seg.paths, _first(r, *FRACTION_KEYS)),
            "planning_time_s": _number(_first(r, *PLANNING_KEYS)),
            "min_arm_distance_m": d,
            "closest_pair": list(pair) if pair else None,
            "distance_source": source,
            "checks_passed": _checks_passed(r, gate),
        }
    )
    described: dict[str, Any] = {
        "step": int(seg.step),
        "label": seg.label,
        "arms": {p.arm: p.kind for p in seg.paths},
        "before": [_gripper(e) for e in seg.before],
        "after": [_gripper(e) for e in seg.after],
        "closed_chain": list(seg.closed_chain) if seg.closed_chain else None,
        "keep_distance": list(seg.keep_distance) if seg.keep_distance else None,
        "facts": jsonable(seg.facts),
    }
    for key, value in described.items():
        out.setdefault(key, value)
    out["step"] = int(seg.step)  # the timeline groups by it: the segment's own, always
    return out


def _first(r: Mapping[str, Any], *keys: str) -> Any:
    return next((r[k] for k in keys if r.get(k) is not None), None)


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float | np.number):
        return None
    f = float(value)
    return f if np.isfinite(f) else None


def _fractions(paths: Iterable[Any], value: Any) -> dict[str, float | None]:
    """Each moving arm's Cartesian path fraction; None for a transit move or when unknown."""
    out: dict[str, float | None] = {}
    for p in paths:
        if isinstance(value, Mapping):
            out[p.arm] = _number(value.get(p.arm))
        else:
            out[p.arm] = _number(value) if p.kind == "cartesian" else None
    return out


def _reported_distance(
    r: Mapping[str, Any], gate: Any
) -> tuple[float | None, tuple[str, str] | None, str | None]:
    d = _number(_first(r, *DISTANCE_KEYS))
    pair = _first(r, *PAIR_KEYS)
    if d is None and gate is not None:
        d, pair = (
            _number(getattr(gate, "min_arm_distance", None)),
            getattr(gate, "closest_pair", None),
        )
    if d is None:
        return None, None, None
    named = (str(pair[0]), str(pair[1])) if isinstance(pair, Sequence) and len(pair) == 2 else None
    return d, named, "executor"


def _checks_passed(r: Mapping[str, Any], gate: Any) -> bool | None:
    if isinstance(r.get("checks_passed"), bool | np.bool_):
        return bool(r["checks_passed"])
    checks = r.get("checks")
    if isinstance(checks, bool | np.bool_):
        return bool(checks)
    if isinstance(checks, Mapping):
        values = [v for v in checks.values() if isinstance(v, bool | np.bool_)]
        return all(values) if values else None
    if isinstance(checks, list | tuple):
        return len(checks) == 0
    ok = getattr(gate if gate is not None else checks, "ok", None)
    return bool(ok) if isinstance(ok, bool | np.bool_) else None


def _gripper(e: GripperEvent) -> dict[str, Any]:
    return {"arm": e.arm, "mode": e.mode, "holds": e.holds}


# ---------------------------------------------------------------------------------- steps


def _steps(segments: Sequence[Mapping[str, Any]], labels: Mapping[int, str]) -> list[Any]:
    by_step: dict[int, list[Mapping[str, Any]]] = {}
    for s in segments:
        by_step.setdefault(int(s["step"]), []).append(s)
    return [_step(step, labels[step], parts) for step, parts in sorted(by_step.items())]


def _step(step: int, label: str, parts: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    start = min(float(p["start_s"]) for p in parts)
    end = max(float(p["end_s"]) for p in parts)
    d, pair = _closest(parts)
    return {
        "step": step,
        "label": label,
        "start_s": start,
        "end_s": end,
        "duration_s": end - start,
        "segments": [int(p["index"]) for p in parts],
        "strategies": sorted({str(p["strategy"]) for p in parts}),
        "planning_time_s": _sum(p.get("planning_time_s") for p in parts),
        "min_arm_distance_m": d,
        "closest_pair": pair,
        "checks_passed": _all(p.get("checks_passed") for p in parts),
    }


def _closest(parts: Iterable[Mapping[str, Any]]) -> tuple[float | None, list[str] | None]:
    known = [p for p in parts if p.get("min_arm_distance_m") is not None]
    if not known:
        return None, None
    best = min(known, key=lambda p: float(p["min_arm_distance_m"]))
    return float(best["min_arm_distance_m"]), best.get("closest_pair")


def _sum(values: Iterable[Any]) -> float | None:
    known = [float(v) for v in values if v is not None]
    return sum(known) if known else None


def _all(values: Iterable[Any]) -> bool | None:
    """False if any is False; True if all are True; None if some are unknown and none False."""
    vals = list(values)
    if any(v is False for v in vals):
        return False
    return True if vals and all(v is True for v in vals) else None


def _totals(
    program: Program, segments: Sequence[Mapping[str, Any]], steps: Sequence[Mapping[str, Any]]
) -> dict[str, Any]:
    d, pair = _closest(segments)
    start = program.segments[0].trajectory.start_time if program.segments else 0.0
    return {
        "cycle_time_s": program.duration - start,
        "cycle_time_by_merge_s": _by_merge(program.duration - start, segments),
        "segments": len(segments),
        "steps": len(steps),
        "events": len(program.events),
        "planning_time_s": _sum(s.get("planning_time_s") for s in segments),
        "min_arm_distance_m": d,
        "closest_pair": pair,
        "checks_passed": _all(s.get("checks_passed") for s in segments),
        "clearance": {k: _least_clearance(segments, k) for k in ("arms", "environment")},
    }


def _least_clearance(segments: Sequence[Mapping[str, Any]], kind: str) -> dict[str, Any] | None:
    """The least ``clearance[kind]`` over the segments, with the segment's index and label."""
    found = [
        (s, c[kind])
        for s in segments
        if isinstance(c := s.get("clearance"), Mapping) and isinstance(c.get(kind), Mapping)
    ]
    if not found:
        return None
    s, least = min(found, key=lambda f: float(f[1]["distance_m"]))
    return {**least, "segment": int(s["index"]), "label": s.get("label")}


def _by_merge(cycle: float, segments: Sequence[Mapping[str, Any]]) -> dict[str, float]:
    """The cycle time had every segment been timed with each merge in its ``durations_s``:
    the run's cycle with each segment's chosen merge swapped for the other (delays kept;
    segments not merged, one arm or scheduled apart, unchanged). Empty when no segment
    reports merges."""
    names = sorted({m for s in segments for m in (s.get("durations_s") or {})})
    out: dict[str, float] = {}
    for name in names:
        total = cycle
        for s in segments:
            durations = s.get("durations_s") or {}
            if s.get("merge") in durations and name in durations:
                total += float(durations[name]) - float(durations[s["merge"]])
        out[name] = total
    return out


def _arms(program: Program, cell: CellModel | None) -> list[str]:
    if cell is not None:
        return list(cell.arms)
    seen: dict[str, None] = {}
    for cs in program.segments:
        for arm in cs.segment.arms():
            seen.setdefault(arm, None)
    return list(seen)
