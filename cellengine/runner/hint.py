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
    from cellengine.info.load import LoadedPlan


def resume_command(loaded: LoadedPlan, execution: str, speed: float, run_dir: Path) -> str:
    """``cellengine run PLAN --resume RUN_DIR``, with ``--cell``, ``--execution`` and
    ``--speed`` when the run was started with them (a resume must give the same)."""
    plan = loaded.plan
    words = ["cellengine", "run", display_path(plan.file), "--resume", display_path(run_dir)]
    cell = loaded.world.cell_file
    if cell.resolve() != (plan.file.parent / plan.cell).resolve():
        words += ["--cell", display_path(cell)]
    if execution != plan.execution:
        words += ["--execution", execution]
    if speed != 1.0:
        words += ["--speed", f"{speed:g}"]
    return shlex.join(words)


@contextlib.contextmanager
def resumable(command: str) -> Iterator[None]:
    """A fault or a Ctrl-C inside ends the run saying how to go on (``command``): a fault as
    it is (exit 3), a Ctrl-C as an interruption (exit 2). A refusal moved nothing: there is
    nothing to go on with."""
    hint = Problem(f"to go on from where it stopped: {command}")
    try:
        yield
    except DriverFault as e:
        raise DriverError([*e.problems, hint]) from None
    except KeyboardInterrupt:
        raise UsageError([Problem("interrupted; both arms stopped"), hint]) from None
