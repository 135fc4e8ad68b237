"""What ends a run goes on record: a driver fault in the journal (for ``--resume``), and how
the driver's real-time loop kept its period in the journal and on screen, and what the run did
in its report."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING

from cellengine.journal import Entry, append

if TYPE_CHECKING:
    from cellengine.drivers.base import Driver
    from cellengine.pipeline import Compiled


@contextlib.contextmanager
def timed(
    journal: IO[str], driver: Driver, out: Path, quiet: bool, compiled: Compiled
) -> Iterator[None]:
    """Whatever happens inside, afterwards: how the driver's real-time loop kept its period
    (a real driver's), journaled and printed; and what the run did in report.json's and
    report.html's ``run`` (written as ``running`` first: a report that still says so was
    killed)."""
    from cellengine.report.outcome import write_run
    from cellengine.runner.ran import run_summary

    write_run(out, run_summary(compiled, driver.kind, out, running=True))
    failure: BaseException | None = None
    try:
        yield
    except BaseException as e:
        failure = e
        raise
    finally:
        timing = driver.timing()
        if timing is not None:
            from cellengine.drivers.servo_timing import describe

            append(journal, Entry.TIMING, servo=timing)
            if not quiet:
                print(describe(timing))
        summary = run_summary(
            compiled, driver.kind, out, failure, servo=timing, stopped=driver.fault
        )
        write_run(out, summary)


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
        more = {} if e.streams is None else {"streams": e.streams}
        append(journal, Entry.FAULT, fault={**e.fault.to_json(), **stopped}, **more)
        raise
