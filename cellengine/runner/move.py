"""Moving the arms to where a segment starts, when they are not there: a planned, gated,
collision-free move (journaled), only from near where the run expects them."""

from __future__ import annotations

from typing import IO, TYPE_CHECKING, Any

import numpy as np

from cellengine.journal import Entry, append
from cellengine.runner.outcome import journaled

if TYPE_CHECKING:
    from cellengine.drivers.base import Driver
    from cellengine.pipeline import Compiled


def move_to(
    compiled: Compiled, driver: Driver, journal: IO[str], index: int, left: Any = None
) -> None:
    """When the arms are not where segment ``index`` starts (real arms left elsewhere, or
    stopped by a fault), a planned, gated, collision-free move there first (journaled).
    Only from near where the run expects them: the segment's start, or ``left``, where
    the journal says an earlier run left them (a fault may stop them far into a segment)."""
    from cellengine.execute.recovery import recovery_segment

    segment = compiled.program.segments[index]
    q_now = driver.joint_state()
    target = segment.trajectory.q[0]
    if float(np.max(np.abs(q_now - target))) <= driver.start_tolerance:
        return
    label = segment.segment.label
    if left is None:
        _check_move_limit(driver, q_now, target[None, :], f"'{label}' starts")
    else:  # a killed run journals no stop: the arms may be anywhere along the segment
        near = np.vstack([np.asarray(left, dtype=float)[None, :], segment.trajectory.q])
        _check_move_limit(driver, q_now, near, f"the run left it (in or before '{label}')")
    holds = {arm: driver.gripper(arm).holds for arm in compiled.cell.arms}
    move = recovery_segment(
        compiled.world,
        compiled.cell,
        compiled.context.scene,
        q_now,
        target,
        holds,
        driver.start_tolerance,
        segment.segment.step,
    )
    if move is None:
        return
    append(journal, Entry.RECOVERY, label=move.segment.label, duration=move.trajectory.duration)

    def go() -> None:
        assert move is not None
        driver.execute(move)

    journaled(journal, driver, go)


def _check_move_limit(driver: Driver, q_now: Any, expected: Any, where: str) -> None:
    """Arms far from every place the run expects them (rows of ``expected``) were put there
    on purpose, or by someone who does not know this run: they are not moved on their own
    (the driver's ``start_move_limit``)."""
    from cellengine.drivers.fault import DriverRefused

    offs = np.abs(q_now[None, :] - expected)
    nearest = int(np.argmin(offs.max(axis=1)))
    target, off = expected[nearest], offs[nearest]
    j = int(np.argmax(off))
    if off[j] <= driver.start_move_limit:
        return
    arm, joint = driver.layout.arm_of(j), driver.joint_names[j]
    raise DriverRefused(
        driver.kind,
        f"arm '{arm}' joint '{joint}' is at {q_now[j]:.4f}, {off[j]:.4f} rad from where "
        f"{where} ({target[j]:.4f}): farther than start_move_limit "
        f"({driver.start_move_limit:g} rad), so the run does not move it there on its own; "
        "jog the arms closer, or raise the driver's start_move_limit in the cell file",
    )
