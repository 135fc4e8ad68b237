"""What a run did, for report.json's ``run`` (and the page's status): how it ended, read from
what ended it and from its journal (the segments finished, resumes, load-cell readings,
replannings since its ``start``), with the runtime choices the masses resolved.

``outcome``: ``running`` (written when the arms start: a report still saying so was killed),
``completed``, ``fault`` (``fault``: kind, arm, joint, time, message), ``interrupted``
(Ctrl-C) or ``error`` (anything else that stopped it: ``message``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cellengine.journal import JOURNAL, Entry

if TYPE_CHECKING:
    from cellengine.drivers.fault import Fault
    from cellengine.pipeline import Compiled


def outcome_of(
    failure: BaseException | None, stopped: Fault | None = None
) -> tuple[str, dict[str, Any] | None, str | None]:
    """The outcome, the fault (as journaled) and a message for what ended a run; ``stopped``:
    the driver's fault, which tells when an interrupt outside its loop stopped the arms."""
    from cellengine.drivers.fault import DriverFault

    if failure is None:
        return "completed", None, None
    if isinstance(failure, KeyboardInterrupt):
        fault = stopped.to_json() if stopped is not None else None
        return "interrupted", fault, "interrupted (Ctrl-C)"
    if isinstance(failure, DriverFault):
        fault = failure.fault.to_json()
        kind = "interrupted" if failure.fault.kind == "interrupted" else "fault"
        return kind, fault, failure.fault.message
    return "error", None, str(failure) or type(failure).__name__


def run_summary(
    compiled: Compiled,
    driver: str,
    out: Path,
    failure: BaseException | None = None,
    *,
    running: bool = False,
    servo: dict[str, Any] | None = None,
    stopped: Fault | None = None,
) -> dict[str, Any]:
    """report.json's ``run`` (see the module's notes) for the run in folder ``out``."""
    outcome, fault, message = ("running", None, None) if running else outcome_of(failure, stopped)
    entries = _this_run(out / JOURNAL)
    measured: list[dict[str, Any]] = [
        {k: e.get(k) for k in ("step", "object", "arm", "mass_kg")}
        for e in entries
        if e["entry"] == Entry.MEASURED and isinstance(e.get("mass_kg"), int | float)
    ]
    masses = {str(m["object"]): float(m["mass_kg"]) for m in measured}
    return {
        "driver": driver,
        "outcome": outcome,
        "message": message,
        "fault": fault,
        "segments": _segments(out, compiled),
        "segments_finished": _finished(entries),
        "stopped_in": None if outcome in ("running", "completed") else _unfinished(entries),
        "resumed": [
            {"from_segment": e.get("from_segment"), "label": e.get("label")}
            for e in entries
            if e["entry"] == Entry.RESUME
        ],
        "replanned": sum(1 for e in entries if e["entry"] == Entry.REPLANNED),
        "measured": measured,
        "choices": runtime_choices(compiled, masses),
        "servo": servo,
    }


def runtime_choices(compiled: Compiled, measured: dict[str, float]) -> list[dict[str, Any]]:
    """Each ``heavier_of``/``lighter_of`` of the plan and the object it picks with the masses
    known (``measured``: read by the load cell; ``objects.yaml``: the file's, where one of its
    objects was not weighed); None where a mass is known neither way."""
    from cellengine.choices import candidates, known_masses, resolve
    from cellengine.skill import HeavierOf, LighterOf

    known = known_masses(compiled.world, measured)
    out: list[dict[str, Any]] = []
    for i, step in enumerate(compiled.loaded.plan.steps):
        for field in type(step).model_fields:
            ref = getattr(step, field)
            if not isinstance(ref, HeavierOf | LighterOf):
                continue
            names = candidates(ref)
            ok = all(n in known for n in names)
            out.append(
                {
                    "step": i,
                    "field": field,
                    "rule": "heavier_of" if isinstance(ref, HeavierOf) else "lighter_of",
                    "of": list(names),
                    "chose": resolve(ref, known) if ok else None,
                    "by": "measured" if all(n in measured for n in names) else "objects.yaml",
                }
            )
    return out


def _segments(out: Path, compiled: Compiled) -> int:
    """The program's segments: the last one written to the folder's report (a replanned run's
    program is not ``compiled``'s); both robots at once: the segments of their streams."""
    from cellengine.report.write import REPORT_JSON

    program = compiled.program
    try:
        report = json.loads((out / REPORT_JSON).read_text(encoding="utf-8"))
        streams = report.get("streams") or {}
        if streams.get("at_once"):
            return len({s["segment"] for lane in streams["lanes"].values() for s in lane})
        return int(report["totals"]["segments"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        if program.streams:
            return len(program.streams) + len(program.done)
        return len(program.segments)


def _this_run(journal: Path) -> list[dict[str, Any]]:
    """The journal's entries since its last ``start`` (a torn or unreadable line skipped:
    this is for the report; ``--resume`` checks every line itself)."""
    entries: list[dict[str, Any]] = []
    if not journal.is_file():
        return entries
    for line in journal.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            entry = json.loads(line)
        except ValueError:
            continue
        if not isinstance(entry, dict) or "entry" not in entry:
            continue
        if entry["entry"] == Entry.START:
            entries = []
        entries.append(entry)
    return entries


def _finished(entries: list[dict[str, Any]]) -> int:
    """Segments finished in order (a resumed or replanned run may finish one again); both
    robots at once: the segments of their streams finished."""
    done = 0
    for e in entries:
        if e["entry"] == Entry.FINISHED and isinstance(e.get("segment"), int):
            streams = e.get("streams")
            done = len(streams["done"]) if isinstance(streams, dict) else e["segment"] + 1
    return done


def _unfinished(entries: list[dict[str, Any]]) -> dict[str, Any] | None:
    """The segment sent and not finished when the run stopped, if any."""
    sent: dict[str, Any] | None = None
    for e in entries:
        if e["entry"] == Entry.SENT:
            sent = {"segment": e.get("segment"), "label": e.get("label")}
        elif e["entry"] == Entry.FINISHED:
            sent = None
    return sent
