"""What a run shows while the arms move: the step (as the plan says it), the segment, and the
program's time so far against its whole, updated by the runner before each segment is sent,
never from the driver's servo loop (which must keep its 2 ms period).

On a terminal it is a live line drawn with rich (no refresh thread: it is redrawn only
between segments); elsewhere (a CI log, a file) one plain line per segment; with ``-q``
nothing.
"""

from __future__ import annotations

import sys
from typing import IO, TYPE_CHECKING, Protocol

from cellengine.errors import printable

if TYPE_CHECKING:
    from cellengine.pipeline import Compiled


class Live(Protocol):
    def cycle(self, cycle: int, cycles: int) -> None:
        """Cycle ``cycle`` of ``cycles`` begins."""

    def segment(self, compiled: Compiled, index: int) -> None:
        """Segment ``index`` of ``compiled``'s program is about to be sent."""

    def close(self) -> None:
        """The run is over (done or stopped)."""


def live(compiled: Compiled, quiet: bool, stream: IO[str] | None = None) -> Live:
    """The display for a run of ``compiled``: nothing when ``quiet``, rich on a terminal,
    plain lines otherwise (on ``stream``, default standard error)."""
    if quiet:
        return Silent()
    out = sys.stderr if stream is None else stream
    return Bar(compiled, out) if out.isatty() else Lines(out)


class Silent:
    def cycle(self, cycle: int, cycles: int) -> None:
        pass

    def segment(self, compiled: Compiled, index: int) -> None:
        pass

    def close(self) -> None:
        pass


def describe(compiled: Compiled, index: int, cycle: int = 1, cycles: int = 1) -> tuple[str, str]:
    """One segment in words, what and when: ``step 2/3 PlaceConnector cable1:
    routing.connector, segment 9/38 'PlaceConnector routing.connector: approach'`` (with
    ``cycle 1/2, `` first when there are several) and ``5.20 s of 25.74 s``."""
    from cellengine.pipeline import step_label

    program, steps = compiled.program, compiled.loaded.plan.steps
    seg = program.segments[index]
    step = seg.segment.step
    head = f"cycle {cycle}/{cycles}, " if cycles > 1 else ""
    what = (
        f"{head}step {step + 1}/{len(steps)} {step_label(steps[step])}, "
        f"segment {index + 1}/{len(program.segments)} '{seg.segment.label}'"
    )
    return printable(what), f"{seg.trajectory.start_time:.2f} s of {program.duration:.2f} s"


class Lines:
    """One line per segment: for logs."""

    def __init__(self, stream: IO[str]) -> None:
        self.stream = stream
        self.at = (1, 1)

    def cycle(self, cycle: int, cycles: int) -> None:
        self.at = (cycle, cycles)

    def segment(self, compiled: Compiled, index: int) -> None:
        what, when = describe(compiled, index, *self.at)
        print(f"{what}, {when}", file=self.stream, flush=True)

    def close(self) -> None:
        pass


class Bar:
    """A rich progress bar over the program's time, redrawn before each segment."""

    def __init__(self, compiled: Compiled, stream: IO[str]) -> None:
        from rich.console import Console
        from rich.markup import escape
        from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
        from rich.table import Column

        self.progress = Progress(
            BarColumn(bar_width=24),
            TextColumn("{task.fields[when]}"),
            TimeElapsedColumn(),
            # what wraps rather than be cut: the segment's label is at its end
            TextColumn("{task.description}", table_column=Column(no_wrap=False, ratio=1)),
            console=Console(file=stream),
            auto_refresh=False,  # no thread beside the servo loop: redrawn between segments
            redirect_stdout=False,  # standard output may be a pipe: it stays one
            redirect_stderr=False,
        )
        total = compiled.program.duration or 1.0
        self.task = self.progress.add_task("", total=total, when="")
        self.at = (1, 1)
        self.escape = escape
        self.progress.start()

    def cycle(self, cycle: int, cycles: int) -> None:
        self.at = (cycle, cycles)

    def segment(self, compiled: Compiled, index: int) -> None:
        t = compiled.program.segments[index].trajectory.start_time
        total = compiled.program.duration or 1.0
        what, when = describe(compiled, index, *self.at)
        what = self.escape(what)  # names from files are not rich markup
        self.progress.update(self.task, completed=t, total=total, description=what, when=when)
        self.progress.refresh()

    def close(self) -> None:
        self.progress.stop()
