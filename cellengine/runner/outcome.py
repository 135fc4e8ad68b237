"""What ends a run goes on record: a driver fault in the journal (for ``--resume``), and how
the driver's real-time loop kept its period in the journal, on screen and in report.json."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING

from cellengine.journal import Entry, append

if TYPE_CHECKING:
    from cellengine.drivers.base import Driver


@contextlib.contextmanager
def timed(journal: IO[str], driver: Driver, out: Path, quiet: bool) -> Iterator[None]:
    """Whatever happens inside, afterwards: how the driver's real-time loop kept its period
    (a real driver's), journaled, printed, and in report.json's ``run``."""
    outcome = "fault"
    try:
        yield
        outcome = "completed"
    finally:
        timing = driver.timing()
        if timing is not None:
            from cellengine.drivers.servo_timing import describe
            from cellengine.outfiles import write_files
            from cellengine.report.write import REPORT_JSON

            append(journal, Entry.TIMING, servo=timing)
            report = json.loads((out / REPORT_JSON).read_text())
            report["run"] = {"driver": driver.kind, "outcome": outcome, "servo": timing}
            write_files(out, {REPORT_JSON: json.dumps(report) + "\n"})
            if not quiet:
                print(describe(timing))


def journaled(journal: IO[str], driver: Driver, play: Callable[[], None]) -> None:
    """``play()``; a driver fault is journaled (what, where, when, the controller's safety
    bits, where the arms stopped) before it ends the run, so that ``--resume`` knows."""
    from cellengine.drivers.fault import DriverFault
    from cellengine.drivers.record import FaultRecord

    try:
        play()
    except DriverFault as e:
        record = next(
            (r for r in reversed(driver.recorder.entries) if isinstance(r, FaultRecord)), None
        )
        stopped = record.to_json() if record is not None else {}
        stopped.pop("entry", None)
        append(journal, Entry.FAULT, fault={**e.fault.to_json(), **stopped})
        raise
