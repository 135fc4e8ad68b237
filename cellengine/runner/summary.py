"""What a run will do, in the words the confirmation before real arms move gives: how long
the arms move, how fast at most, and at what share of their limits."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from cellengine.pipeline import Compiled

PERCENT = 100.0


def motion_summary(compiled: Compiled, cycles: int = 1) -> str:
    """``25.74 s of motion; at most 1.05 rad/s (left_elbow_joint) and 0.70 m/s at a TCP
    (right); timed at 100 % of the joints' velocity and acceleration limits``, with the
    cycles, the TCP speed cap and ``--speed`` when there are."""
    from cellengine.motion.speed import tcp_speeds
    from cellengine.motion.trajectory import concatenate

    program, cell, speed = compiled.program, compiled.cell, compiled.context.speed
    traj = concatenate([s.trajectory for s in program.segments])
    joint_peaks = np.abs(traj.qd).max(axis=0)
    j = int(np.argmax(joint_peaks))
    tcp = {arm: float(v.max()) for arm, v in tcp_speeds(cell, traj, dt=0.01).items()}
    arm = max(tcp, key=lambda a: tcp[a])
    duration = f"{program.duration:.2f} s of motion"
    if cycles > 1:
        duration += f" per cycle, {cycles} cycles ({program.duration * cycles:.2f} s)"
    scaled = (
        f"{speed.velocity * PERCENT:.0f} % of the joints' velocity limits and "
        f"{speed.acceleration * PERCENT:.0f} % of their acceleration limits"
    )
    if speed.velocity == speed.acceleration:
        scaled = f"{speed.velocity * PERCENT:.0f} % of the joints' velocity and acceleration limits"
    cap = "" if speed.tcp is None else f", the TCPs capped at {speed.tcp:.3f} m/s"
    factor = "" if speed.factor == 1.0 else f" (--speed {speed.factor:g})"
    unit = joint_unit(compiled, traj.joint_names[j]) + "/s"
    return (
        f"{duration}; at most {joint_peaks[j]:.2f} {unit} ({traj.joint_names[j]}) and "
        f"{tcp[arm]:.2f} m/s at a TCP ({arm}); timed at {scaled}{cap}{factor}"
    )


def joint_unit(compiled: Compiled, joint: str) -> str:
    """A joint's position unit: m for a prismatic joint, else rad."""
    model = compiled.cell.model
    kind = str(model.joints[model.getJointId(joint)].shortname())
    return "m" if kind.startswith("JointModelP") else "rad"  # PX, PY, PZ, PrismaticUnaligned
