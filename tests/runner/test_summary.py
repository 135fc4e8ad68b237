"""The confirmation before real arms move states the run's duration, peak speeds and the
speed scaling it was timed with."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from cellengine.motion.speed import Speed
from cellengine.motion.trajectory import concatenate
from cellengine.pipeline import Compiled
from cellengine.runner.summary import motion_summary


def _peaks(compiled: Compiled) -> tuple[str, str]:
    """The fastest joint (rad/s, its name) and TCP (m/s, its arm), from finite differences
    of positions every 1 ms: another way to the same figures."""
    cell = compiled.cell
    traj = concatenate([s.trajectory for s in compiled.program.segments])
    t = np.arange(traj.start_time, traj.end_time, 0.001)
    q, _, _ = traj.sample(t)
    joints = np.abs(np.diff(q, axis=0)).max(axis=0) / 0.001
    j = int(np.argmax(joints))
    tcp = {
        arm: np.linalg.norm(
            np.diff([cell.arms[arm].fk(row[s])[:3, 3] for row in q], axis=0), axis=1
        ).max()
        / 0.001
        for arm, s in cell.slices.items()
    }
    arm = max(tcp, key=lambda a: tcp[a])
    return (
        f"{joints[j]:.2f} rad/s ({traj.joint_names[j]})",
        f"{tcp[arm]:.2f} m/s at a TCP ({arm})",
    )


def test_the_duration_peaks_and_speed_are_stated(cycling: Compiled) -> None:
    joint, tcp = _peaks(cycling)
    d = cycling.program.duration
    assert motion_summary(cycling) == (
        f"{d:.2f} s of motion; at most {joint} and {tcp}; timed at 100 % of the joints' "
        "velocity and acceleration limits"
    )
    slowed = replace(cycling, context=cycling.context.with_speed(Speed(0.4, 0.25, 0.125, 0.5)))
    assert motion_summary(slowed, 3) == (
        f"{d:.2f} s of motion per cycle, 3 cycles ({3 * d:.2f} s); at most {joint} and {tcp}; "
        "timed at 40 % of the joints' velocity limits and 25 % of their acceleration limits, "
        "the TCPs capped at 0.125 m/s (--speed 0.5)"
    )
