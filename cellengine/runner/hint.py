"""How to go on with a run that stopped: the command, with the run's own paths and options."""

from __future__ import annotations

import contextlib
import shlex
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from cellengine.drivers.fault import DriverFault
from cellengine.errors import DriverError, Problem, UsageError, display_path

if TYPE_CHECKING:
    from cellengine.pipeline import Compiled


def resume_command(compiled: Compiled, run_dir: Path) -> str:
    """``cellengine run PLAN --resume RUN_DIR``, with ``--cell``, ``--execution`` and
    ``--speed`` when the run was started with them (a resume must give the same)."""
    plan = compiled.loaded.plan
    words = ["cellengine", "run", display_path(plan.file), "--resume", display_path(run_dir)]
    cell = compiled.world.cell_file
    if cell.resolve() != (plan.file.parent / plan.cell).resolve():
        words += ["--cell", display_path(cell)]
    if compiled.strategy != plan.execution:
        words += ["--execution", compiled.strategy]
    if compiled.context.speed.factor != 1.0:
        words += ["--speed", f"{compiled.context.speed.factor:g}"]
    return shlex.join(words)


@contextlib.contextmanager
def resumable(compiled: Compiled, run_dir: Path) -> Iterator[None]:
    """A fault or a Ctrl-C inside ends the run with how to go on after it: a fault as it is
    (exit 3), a Ctrl-C as an interruption (exit 2)."""
    hint = Problem(f"to go on from where it stopped: {resume_command(compiled, run_dir)}")
    try:
        yield
    except DriverFault as e:  # a refusal moved nothing: there is nothing to go on with
        raise DriverError([*e.problems, hint]) from None
    except KeyboardInterrupt:
        raise UsageError([Problem("interrupted; both arms stopped"), hint]) from None
