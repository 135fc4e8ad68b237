"""The fuzz target's runner: the real loaders in a fresh process, judged from outside.

A crash in C (coal's qhull, pinocchio, lxml) kills the process with a signal that no Python
code can catch, and a hang never returns: so each input is loaded in a subprocess with a
timeout. It must end by itself with exit 0, 1 or 2 and print no Python traceback.

``python -m tests.fuzz.target CELL`` does what `cellengine validate --no-compile CELL` does
(through the CLI's own main), then builds the collision scene a compile builds first, where
meshes reach qhull; `validate --no-compile` stops before it.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]  # the checkout whose engine is under test
TRACEBACK = "Traceback (most recent call last)"
EXPECTED_CODES = (0, 1, 2)  # ok, invalid input, usage
TAIL = 3000  # characters of stderr shown on a failure


@dataclass(frozen=True)
class Outcome:
    args: tuple[str, ...]
    code: int | None  # None: still running at the timeout, and killed
    stdout: str  # validate prints its problems here
    stderr: str
    seconds: float
    timeout: float


def run_python(args: list[str], timeout: float, cwd: Path = ROOT) -> Outcome:
    """``python -X faulthandler ARGS`` on this checkout's engine; faulthandler prints where a
    signal struck (the exit code stays the signal's)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    start = time.monotonic()
    try:
        done = subprocess.run(
            [sys.executable, "-X", "faulthandler", *args],
            cwd=cwd,
            env=env,
            stdin=subprocess.DEVNULL,
            capture_output=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired as e:  # run() has killed it
        out, err = _text(e.stdout), _text(e.stderr)
        return Outcome(tuple(args), None, out, err, time.monotonic() - start, timeout)
    out, err = _text(done.stdout), _text(done.stderr)
    return Outcome(tuple(args), done.returncode, out, err, time.monotonic() - start, timeout)


def _text(data: bytes | str | None) -> str:
    return data.decode(errors="replace") if isinstance(data, bytes) else data or ""


def load_cell(cell: Path, timeout: float) -> Outcome:
    """This module's main on ``cell`` (a cell.yaml) in a subprocess."""
    return run_python(["-m", "tests.fuzz.target", str(cell)], timeout)


def cellengine(args: list[str], timeout: float) -> Outcome:
    """`cellengine ARGS` in a subprocess, from the checkout's root."""
    return run_python(["-m", "cellengine", *args], timeout)


def faults(o: Outcome) -> list[str]:
    """What is wrong with how the process ended; empty when it ended as promised."""
    out = []
    if o.code is None:
        out.append(f"still running after {o.timeout:g} s (killed)")
    elif o.code < 0:
        out.append(f"killed by signal {_signal_name(-o.code)}")
    elif o.code not in EXPECTED_CODES:
        out.append(f"exit code {o.code}")
    if TRACEBACK in o.stderr:
        out.append("a traceback on stderr")
    return out


def assert_clean(o: Outcome, shown: str = "") -> None:
    """Fail with the command, what went wrong, ``shown`` (the input) and stderr's tail."""
    bad = faults(o)
    if bad:
        raise AssertionError(
            f"{' '.join(o.args)}: {'; '.join(bad)}\n--- input ---\n{shown}\n"
            f"--- stdout (its end) ---\n{o.stdout[-TAIL:]}\n"
            f"--- stderr (its end) ---\n{o.stderr[-TAIL:]}"
        )


def _signal_name(n: int) -> str:
    try:
        return signal.Signals(n).name
    except ValueError:
        return str(n)


def _load_scene(cell: str) -> int:
    from cellengine.cli import main
    from cellengine.errors import CellError

    code = main(["validate", "--no-compile", cell])
    if code:
        return code
    from cellengine.context import build_context
    from cellengine.info.load import load_world

    try:  # the CLI's handling of errors (cellengine/cli.py), around what a compile does first
        build_context(load_world(Path(cell)))
    except CellError as e:
        for problem in e.problems:
            print(problem, file=sys.stderr)
        return e.exit_code
    return 0


if __name__ == "__main__":
    sys.exit(_load_scene(sys.argv[1]))
