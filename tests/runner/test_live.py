"""What a run shows while the arms move: one line per segment in a log, a rich bar on a
terminal, nothing with -q."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from cellengine.pipeline import Compiled
from cellengine.runner import DriverOptions, run_plan
from cellengine.runner.live import Bar, Lines, Silent, live


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


STEPS = (
    "step 1/3 PickCable cable1: holder.comb_a, holder.comb_b",
    "step 2/3 PlaceConnector cable1: routing.connector",
    "step 3/3 RouteCable cable1: routing.guide1, routing.guide2, routing.guide3",
)


def _line(compiled: Compiled, index: int, head: str = "") -> str:
    seg = compiled.program.segments[index]
    step = STEPS[seg.segment.step]
    n = len(compiled.program.segments)
    return (
        f"{head}{step}, segment {index + 1}/{n} '{seg.segment.label}', "
        f"{seg.trajectory.start_time:.2f} s of {compiled.program.duration:.2f} s"
    )


def test_a_log_gets_a_line_per_segment(cycling: Compiled) -> None:
    out = io.StringIO()
    shown = live(cycling, quiet=False, stream=out)
    assert isinstance(shown, Lines)
    shown.segment(cycling, 0)
    shown.cycle(2, 3)
    last = len(cycling.program.segments) - 1
    shown.segment(cycling, last)
    assert out.getvalue().splitlines() == [
        _line(cycling, 0),
        _line(cycling, last, "cycle 2/3, "),
    ]
    assert _line(cycling, last).endswith("'return home', 25.74 s of 28.33 s")


def test_a_terminal_gets_a_bar_and_quiet_nothing(cycling: Compiled) -> None:
    term = Terminal()
    shown = live(cycling, quiet=False, stream=term)
    assert isinstance(shown, Bar)
    shown.segment(cycling, 1)
    shown.close()
    shown_text = term.getvalue()
    start = cycling.program.segments[1].trajectory.start_time
    assert f"{start:.2f} s of {cycling.program.duration:.2f} s" in shown_text
    assert "step 1/3 PickCable cable1" in shown_text and "segment 2/39" in shown_text
    assert isinstance(live(cycling, quiet=True, stream=term), Silent)


def test_a_run_shows_each_segment_before_it_is_sent(
    cycling: Compiled, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run_plan(cycling, tmp_path / "run", DriverOptions(), yes=False, quiet=False)
    err = capsys.readouterr().err.splitlines()
    n = len(cycling.program.segments)
    assert err == [_line(cycling, i) for i in range(n)]
    run_plan(cycling, tmp_path / "quiet", DriverOptions(), yes=False, quiet=True)
    assert capsys.readouterr() == ("", "")
