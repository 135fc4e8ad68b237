"""A run's journal.jsonl: written as the run goes (:func:`append`, by cellengine/runner/),
read back for ``run --resume`` (:func:`read_progress`): how far the run got.

The journal is append-only, one JSON object per line, on disk at each entry (:class:`Entry`):
``start`` (with the run's identity: what it was compiled from, see
:mod:`cellengine.runner.identity`; a new run into the folder starts afresh) or ``resume``,
``recovery`` (a move to where a segment starts), then per segment
``sent`` and ``finished`` (with the arms' q and grippers after it; when the arms work at
once, ``streams``: each robot's segments finished and running then), ``measured`` (a load
cell), ``tool`` (a tool changer locked a tool, or unlocked leaving one in its slot, at the
end of a segment, before its ``finished``), ``tared`` (each load cell's zero, taken with its
gripper empty when the run started: a resumed run, whose gripper may hold something, uses
it), ``replanned``, ``cycle`` (``run --cycles N``: the program begins again; the start says
how many cycles),
``fault`` (what stopped the run), ``timing`` (the servo loop's), ``end``.
A run killed at any moment leaves whole lines and at most one torn last line, which is
ignored; any other line that is not a JSON object is an error at its line. So is every value
``--resume`` would act on that is not what the runner writes (a journal can be edited or
damaged): a resumed run must not start from a NaN joint or weigh with a mass of 1e308.
"""

from __future__ import annotations

import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import IO, Any

from cellengine.errors import InputError, Problem, display_path, known
from cellengine.info.bounds import MAX_MASS

JOURNAL = "journal.jsonl"  # in the run directory


class Entry(StrEnum):
    """The kinds of journal entry (each line's ``entry``)."""

    START = "start"
    RESUME = "resume"
    RECOVERY = "recovery"
    SENT = "sent"
    FINISHED = "finished"
    MEASURED = "measured"
    TOOL = "tool"
    TARED = "tared"
    REPLANNED = "replanned"
    CYCLE = "cycle"
    FAULT = "fault"
    TIMING = "timing"
    END = "end"


def append(journal: IO[str], kind: Entry, **fields: Any) -> None:
    """One journal line, on disk before the next thing happens."""
    journal.write(json.dumps({"time": time.time(), "entry": kind.value, **fields}) + "\n")
    journal.flush()
    os.fsync(journal.fileno())


# the arms at once: the segments finished and running, and where the program had the arms
StreamState = tuple[frozenset[int], frozenset[int], tuple[float, ...]]


@dataclass(frozen=True)
class Progress:
    """``labels``: the segments finished, in order (the next to run is ``len(labels)``);
    ``q`` and ``grippers``: the arms after the last of them (None before any); ``measured``:
    the load cell's readings; ``ended``: the run reached its end; ``fault``: the last fault
    journaled, if any."""

    labels: tuple[str, ...] = ()
    q: tuple[float, ...] | None = None
    grippers: dict[str, tuple[str | None, str | None]] = field(default_factory=dict)
    measured: dict[str, float] = field(default_factory=dict)
    ended: bool = False
    fault: dict[str, Any] | None = None
    run: dict[str, Any] | None = None  # the run's identity, from its ``start`` entry
    started: bool = False  # the journal has a ``start``: progress is of its last run
    cycle: int = 1  # the cycle ``labels`` are of (run --cycles)
    cycles: int = 1  # the cycles the run was started for
    # each load cell's zero (kg, by arm) as the run's first activation took it
    tares: dict[str, float] = field(default_factory=dict)
    # the arms at once: the segments (of the program's streams) finished and those running
    # where the run stopped (the last segment finished, or a fault), and where the program
    # had the arms then (None: none finished, or one after another)
    streams: StreamState | None = None

    @property
    def done(self) -> int:
        return len(self.labels)


def drop_torn_tail(path: Path) -> None:
    """Cut a torn last line off (a kill while it was written): it never happened, and an
    entry appended to it would make one unreadable line of both."""
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with path.open("r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)


def refuse_unfinished(folder: Path) -> str | None:
    """An error when ``folder``'s journal holds a run that did not end: a new program written
    there would leave that run nothing to resume. A run that ended is replaced: what to say
    about it (None: no earlier run)."""
    path = folder / JOURNAL
    if not path.is_file() or not (progress := read_progress(path)).started:
        return None
    if not progress.ended:
        raise InputError(
            Problem(
                "the run folder holds an unfinished run: go on with it with `cellengine run "
                "PLAN --resume " + str(folder) + "`, or give another --out",
                str(path),
            )
        )
    return (
        f"{display_path(folder)}: replacing the trajectory and report of the run that ended "
        f"there ({JOURNAL} keeps its record)"
    )


def read_progress(path: Path) -> Progress:
    if not path.is_file():
        raise InputError(Problem("no journal.jsonl here: is this a run directory?", str(path)))
    lines = path.read_bytes().split(b"\n")
    entries: list[dict[str, Any]] = []
    done = 0  # the segments the current run finished, in order
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            entry = _entry(line)
            done = _in_order(entry, done)
        except _Bad as e:
            if n == len(lines) and e.torn:
                break  # the last line, torn by a kill (no newline yet): it never happened
            raise InputError(Problem(str(e), str(path), n)) from None
        entries.append(entry)
    return _progress(entries)


def _in_order(entry: dict[str, Any], done: int) -> int:
    """How many segments are finished after ``entry``: a segment finishes after every one
    before it (a replanned or resumed run may finish one again, never skip one)."""
    if entry["entry"] in (Entry.START, Entry.CYCLE):
        return 0
    if entry["entry"] != Entry.FINISHED:
        return done
    segment = int(entry["segment"])
    if segment > done:
        raise _Bad(
            f"segment {segment} finished, but the run's journal has segments finished up to "
            f"{done - 1} only"
            if done
            else f"segment {segment} finished before segment 0"
        )
    return segment + 1


class _Bad(Exception):
    """A journal line that cannot be trusted; ``torn``: what a kill mid-write leaves."""

    def __init__(self, message: str, torn: bool = False) -> None:
        super().__init__(message)
        self.torn = torn


def _entry(line: bytes) -> dict[str, Any]:
    """One line's entry, its values checked as the runner writes them."""
    try:
        entry = json.loads(line.decode("utf-8"))
    except UnicodeDecodeError:
        raise _Bad("not a journal entry (not UTF-8 text)", torn=True) from None
    except ValueError:  # not JSON, or an integer of thousands of digits
        raise _Bad("not a journal entry (JSON)", torn=True) from None
    except RecursionError:
        raise _Bad("not a journal entry (JSON nested too deeply)", torn=True) from None
    if not isinstance(entry, dict) or "entry" not in entry:
        raise _Bad("not a journal entry (no 'entry')")
    kind = entry["entry"]
    if not isinstance(kind, str) or kind not in _KINDS:
        raise _Bad(f"unknown journal entry {_shown(kind)}" + known(_KINDS))
    check = _CHECKS.get(kind)
    if check is not None:
        check(entry)
    return entry


_KINDS = {str(k) for k in Entry}
MAX_JOINT = 100.0  # rad (m for a prismatic joint): no arm turns a joint 16 times
MAX_CYCLES = 1_000_000  # run --cycles


def _field(entry: dict[str, Any], name: str) -> Any:
    if name not in entry:
        raise _Bad(f"'{name}' is missing from this '{entry['entry']}' entry")
    return entry[name]


def _shown(value: Any) -> str:
    """A value as the journal writes it (floats as Python does: nan, inf)."""
    text = repr(value) if isinstance(value, float) else json.dumps(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _finite(value: Any) -> bool:
    """A number that is a finite float: JSON's integers have any number of digits, and one
    of 400 is no float (math.isfinite raises OverflowError on it)."""
    try:
        return _number(value) and math.isfinite(value)
    except OverflowError:
        return False


def _index(value: Any, name: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or value < 0:
        raise _Bad(f"'{name}' must be a segment index (an integer from 0), got {_shown(value)}")
    return value


def _text(value: Any, name: str) -> str:
    if not isinstance(value, str):
        raise _Bad(f"'{name}' must be a string, got {_shown(value)}")
    return value


def _joints(value: Any, name: str) -> None:
    if not isinstance(value, list) or not value:
        raise _Bad(f"'{name}' must be a list of joint values, got {_shown(value)}")
    for i, v in enumerate(value):
        if not _finite(v) or abs(v) > MAX_JOINT:
            raise _Bad(
                f"'{name}[{i}]' must be a finite joint value (rad or m, at most "
                f"{MAX_JOINT:g} either way), got {_shown(v)}"
            )


def _gripper(value: Any, name: str) -> None:
    """[mode, holds]: a jaw mode and the object held, each a name or null."""
    if not (
        isinstance(value, list)
        and len(value) == 2
        and all(v is None or isinstance(v, str) for v in value)
    ):
        raise _Bad(f"'{name}' must be [mode, holds] (each a name or null), got {_shown(value)}")


def _finished(entry: dict[str, Any]) -> None:
    _index(_field(entry, "segment"), "segment")
    _text(_field(entry, "label"), "label")
    _joints(_field(entry, "q"), "q")
    if "streams" in entry:
        _streams(entry["streams"])
    grippers = _field(entry, "grippers")
    if not isinstance(grippers, dict):
        raise _Bad(f"'grippers' must map each arm to [mode, holds], got {_shown(grippers)}")
    for arm, state in grippers.items():
        _gripper(state, f"grippers.{arm}")


def _streams(value: Any) -> None:
    if not isinstance(value, dict) or set(value) != {"done", "running", "q"}:
        raise _Bad(
            "'streams' must map done and running to segment numbers and q to joint values, "
            f"got {_shown(value)}"
        )
    for key in ("done", "running"):
        if not isinstance(value[key], list):
            raise _Bad(f"'streams.{key}' must be a list of segment numbers, got {_shown(value)}")
        for v in value[key]:
            _index(v, f"streams.{key}")
    _joints(value["q"], "streams.q")


def _measured(entry: dict[str, Any]) -> None:
    _text(_field(entry, "object"), "object")
    mass = _field(entry, "mass_kg")
    if not _finite(mass) or not 0 < mass <= MAX_MASS:
        raise _Bad(f"'mass_kg' must be a finite mass in kg (0 to {MAX_MASS:g}), got {_shown(mass)}")


def _tool(entry: dict[str, Any]) -> None:
    _index(_field(entry, "segment"), "segment")
    _text(_field(entry, "arm"), "arm")
    for key in ("tool", "was"):
        value = _field(entry, key)
        if value is not None:
            _text(value, key)


def _tared(entry: dict[str, Any]) -> None:
    zeros = _field(entry, "load_cells")
    if not isinstance(zeros, dict) or not all(
        isinstance(a, str) and _finite(v) and abs(v) <= MAX_MASS for a, v in zeros.items()
    ):
        raise _Bad(
            f"'load_cells' must map arms to finite masses in kg (within {MAX_MASS:g}), "
            f"got {_shown(zeros)}"
        )


def _fault(entry: dict[str, Any]) -> None:
    """Where the fault stopped the arms and grippers: resume starts there."""
    if "streams" in entry:
        _streams(entry["streams"])
    fault = entry.get("fault")
    if fault is None:
        return
    if not isinstance(fault, dict):
        raise _Bad(f"'fault' must be a mapping, got {_shown(fault)}")
    if "q" in fault:
        _joints(fault["q"], "fault.q")
    grippers = fault.get("grippers", [])
    if not isinstance(grippers, list):
        raise _Bad(f"'fault.grippers' must be a list, got {_shown(grippers)}")
    for i, g in enumerate(grippers):
        name = f"fault.grippers[{i}]"
        if not isinstance(g, dict):
            raise _Bad(f"'{name}' must be a mapping of arm, mode, holds, got {_shown(g)}")
        _text(g.get("arm"), f"{name}.arm")
        for key in ("mode", "holds"):  # the runner writes both, null when there is none
            if key not in g:
                raise _Bad(f"'{name}.{key}' is missing from this 'fault' entry")
            if g[key] is not None:
                _text(g[key], f"{name}.{key}")


def _count(value: Any, name: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not 1 <= value <= MAX_CYCLES:
        raise _Bad(f"'{name}' must be a count of cycles (1 to {MAX_CYCLES}), got {_shown(value)}")
    return value


def _cycle(entry: dict[str, Any]) -> None:
    cycle, of = _count(_field(entry, "cycle"), "cycle"), _count(_field(entry, "of"), "of")
    if cycle > of:
        raise _Bad(f"cycle {cycle} of {of}")


def _start(entry: dict[str, Any]) -> None:
    """The run's identity, if any (an older journal has none: resume refuses that itself)."""
    if "cycles" in entry:
        _count(entry["cycles"], "cycles")
    run = entry.get("run")
    if run is not None and not (
        isinstance(run, dict) and all(isinstance(v, str) for v in run.values())
    ):
        raise _Bad(
            "'run' must map plan, cell, objects, execution and version to strings, got "
            + _shown(run)
        )


# the entries whose values resume reads
_CHECKS: dict[str, Callable[[dict[str, Any]], None]] = {
    Entry.START: _start,
    Entry.FINISHED: _finished,
    Entry.MEASURED: _measured,
    Entry.TOOL: _tool,
    Entry.TARED: _tared,
    Entry.FAULT: _fault,
    Entry.CYCLE: _cycle,
}


def _stream_state(value: dict[str, Any]) -> StreamState:
    done, running = (frozenset(int(i) for i in value[k]) for k in ("done", "running"))
    return done, running, tuple(float(v) for v in value["q"])


def _progress(entries: list[dict[str, Any]]) -> Progress:
    labels: list[str] = []
    q: tuple[float, ...] | None = None
    grippers: dict[str, tuple[str | None, str | None]] = {}
    measured: dict[str, float] = {}
    ended, fault = False, None
    run: dict[str, Any] | None = None
    started = False
    cycle, cycles = 1, 1
    streams: StreamState | None = None
    tares: dict[str, float] = {}
    for e in entries:
        kind = e["entry"]
        if kind == Entry.START:  # a new run into the folder: progress is of it alone
            labels, q, grippers, measured, fault = [], None, {}, {}, None
            run, started, streams, tares = e.get("run"), True, None, {}
            cycle, cycles = 1, int(e.get("cycles", 1))
        if kind == Entry.CYCLE:  # the program again from its start, where the arms are
            labels, measured, fault, streams = [], {}, None, None
            cycle, cycles = int(e["cycle"]), int(e["of"])
        if kind == Entry.FINISHED:
            if int(e["segment"]) != len(labels):
                labels = labels[: int(e["segment"])]  # a replanned or resumed run goes on
            labels.append(str(e["label"]))
            fault = None  # the run went on after it
            q = tuple(float(v) for v in e["q"])
            grippers = {str(a): (g[0], g[1]) for a, g in e["grippers"].items()}
            if "streams" in e:
                streams = _stream_state(e["streams"])
        elif kind == Entry.MEASURED:
            measured[str(e["object"])] = float(e["mass_kg"])
        elif kind == Entry.TARED:
            tares = {str(a): float(v) for a, v in e["load_cells"].items()}
        elif kind == Entry.END:
            ended = True
        elif kind == Entry.FAULT:
            fault = dict(e.get("fault") or {})
            if "streams" in e:
                streams = _stream_state(e["streams"])
        elif kind == Entry.START:
            ended = False
    return Progress(
        tuple(labels),
        q,
        grippers,
        measured,
        ended,
        fault,
        run,
        started,
        cycle,
        cycles,
        tares,
        streams,
    )
