"""What the UR driver watches while it streams: pure functions of the readings, so they can be
tested without a controller.

- The controller's safety status bits (RTDE ``safety_status_bits``): bit 2 protective stop;
  bits 5, 6, 7 system, robot and (any) emergency stop; 4 safeguard stop; 9 fault; 10
  stopped for safety (ur-rtde's numbering).
- Tracking: servoJ follows its target with a delay of about the lookahead time, so a joint
  is compared with what was commanded over the last ``lookahead + period``: the deviation
  is the distance to the nearest of those commands.
"""

from __future__ import annotations

import numpy as np

from cellengine.arrays import FloatArray

PROTECTIVE_STOP = 2
SAFEGUARD_STOP = 4
SYSTEM_EMERGENCY_STOP = 5
ROBOT_EMERGENCY_STOP = 6
EMERGENCY_STOP = 7
FAULT = 9
STOPPED_FOR_SAFETY = 10
SAFETY_BITS = {
    0: "normal",
    1: "reduced",
    2: "protective stop",
    3: "recovery",
    4: "safeguard stop",
    5: "system emergency stop",
    6: "robot emergency stop",
    7: "emergency stop",
    8: "violation",
    9: "fault",
    10: "stopped due to safety",
}


def set_bits(bits: int) -> list[str]:
    """The names of the safety status bits set in ``bits``."""
    return [name for bit, name in SAFETY_BITS.items() if bits >> bit & 1]


def safety_stop(bits: int) -> str | None:
    """The fault kind a controller's safety status bits report: ``emergency_stop``,
    ``protective_stop`` (a protective or safeguard stop, a fault, a stop for safety), or
    None when the arm may move."""
    if any(bits >> b & 1 for b in (EMERGENCY_STOP, SYSTEM_EMERGENCY_STOP, ROBOT_EMERGENCY_STOP)):
        return "emergency_stop"
    if any(bits >> b & 1 for b in (PROTECTIVE_STOP, SAFEGUARD_STOP, FAULT, STOPPED_FOR_SAFETY)):
        return "protective_stop"
    return None


def tracking_deviation(measured: FloatArray, recent_commands: FloatArray) -> tuple[int, float]:
    """The joint farthest from every recent command and its distance (rad): per joint, the
    distance to the nearest of ``recent_commands`` (k, n), or to the segment they span."""
    cmds = np.atleast_2d(np.asarray(recent_commands, dtype=np.float64))
    lo, hi = cmds.min(axis=0), cmds.max(axis=0)
    m = np.asarray(measured, dtype=np.float64)
    # a measured value between the commands' extremes was commanded on the way
    dev = np.maximum(lo - m, 0.0) + np.maximum(m - hi, 0.0)
    j = int(np.argmax(dev))
    return j, float(dev[j])
