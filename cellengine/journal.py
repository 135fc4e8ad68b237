"""A run's journal.jsonl: written as the run goes (:func:`append`, by cellengine/runner/),
read back for ``run --resume`` (:func:`read_progress`): how far the run got.

The journal is append-only, one JSON object per line, on disk at each entry (:class:`Entry`):
``start`` (with the run's identity: what it was compiled from, see
:mod:`cellengine.runner.identity`; a new run into the folder starts afresh) or ``resume``,
``recovery`` (a move to where a segment starts), then per segment
``sent`` and ``finished`` (with the arms' q and grippers after it), ``measured`` (a load
cell), ``replanned``, ``fault`` (what stopped the run), ``timing`` (the servo loop's), ``end``.
A run killed at any moment leaves whole lines and at most one torn last line, which is
ignored; any other line that is not a JSON object is an error at its line.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import IO, Any

from cellengine.errors import InputError, Problem

JOURNAL = "journal.jsonl"  # in the run directory


class Entry(StrEnum):
    """The kinds of journal entry (each line's ``entry``)."""

    START = "start"
    RESUME = "resume"
    RECOVERY = "recovery"
    SENT = "sent"
    FINISHED = "finished"
    MEASURED = "measured"
    REPLANNED = "replanned"
    FAULT = "fault"
    TIMING = "timing"
    END = "end"


def append(journal: IO[str], kind: Entry, **fields: Any) -> None:
    """One journal line, on disk before the next thing happens."""
    journal.write(json.dumps({"time": time.time(), "entry": kind.value, **fields}) + "\n")
    journal.flush()
    os.fsync(journal.fileno())


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


def refuse_unfinished(folder: Path) -> None:
    """An error when ``folder``'s journal holds a run that did not end: a new program written
    there would leave that run nothing to resume."""
    path = folder / JOURNAL
    if path.is_file() and not (progress := read_progress(path)).ended and progress.started:
        raise InputError(
            Problem(
                "the run folder holds an unfinished run: go on with it with `cellengine run "
                "PLAN --resume " + str(folder) + "`, or give another --out",
                str(path),
            )
        )


def read_progress(path: Path) -> Progress:
    if not path.is_file():
        raise InputError(Problem("no journal.jsonl here: is this a run directory?", str(path)))
    lines = path.read_text(encoding="utf-8").split("\n")
    entries: list[dict[str, Any]] = []
    for n, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            entry = json.loads(line)
        except json.JSONDecodeError:
            if n == len(lines):
                break  # the last line, torn by a kill (no newline yet): it never happened
            raise InputError(Problem("not a journal entry (JSON)", str(path), n)) from None
        if not isinstance(entry, dict) or "entry" not in entry:
            raise InputError(Problem("not a journal entry (no 'entry')", str(path), n))
        entries.append(entry)
    return _progress(entries)


def _progress(entries: list[dict[str, Any]]) -> Progress:
    labels: list[str] = []
    q: tuple[float, ...] | None = None
    grippers: dict[str, tuple[str | None, str | None]] = {}
    measured: dict[str, float] = {}
    ended, fault = False, None
    run: dict[str, Any] | None = None
    started = False
    for e in entries:
        kind = e["entry"]
        if kind == Entry.START:  # a new run into the folder: progress is of it alone
            labels, q, grippers, measured, fault = [], None, {}, {}, None
            run, started = e.get("run"), True
        if kind == Entry.FINISHED:
            if int(e["segment"]) != len(labels):
                labels = labels[: int(e["segment"])]  # a replanned or resumed run goes on
            labels.append(str(e["label"]))
            fault = None  # the run went on after it
            q = tuple(float(v) for v in e["q"])
            grippers = {str(a): (g[0], g[1]) for a, g in e["grippers"].items()}
        elif kind == Entry.MEASURED:
            measured[str(e["object"])] = float(e["mass_kg"])
        elif kind == Entry.END:
            ended = True
        elif kind == Entry.FAULT:
            fault = dict(e.get("fault") or {})
        elif kind == Entry.START:
            ended = False
    return Progress(tuple(labels), q, grippers, measured, ended, fault, run, started)
