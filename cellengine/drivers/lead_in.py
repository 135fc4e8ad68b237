"""Re-targeting a servo stream onto a segment: the arms stand where the last motion left
them, within the start tolerance of where the next segment starts but rarely exactly there.
Rather than jump the first servo target by that gap, the stream begins with ruckig's
time-optimal, jerk-limited motion from the measured state to the segment's first point
(otg.Retargeter, one sample per servo period), then follows the segment.

The limits are deliberately low (the gap is at most the start tolerance, so the lead-in
lasts a few servo periods) and need no robot model."""

from __future__ import annotations

import numpy as np
import ruckig

from cellengine.arrays import FloatArray
from cellengine.motion.otg import Retargeter

VELOCITY = 0.5  # rad/s
ACCELERATION = 5.0  # rad/s^2
JERK = 250.0  # rad/s^3: accelerations ramp over 20 ms, as the planned motion's do
NO_GAP = 5e-4  # rad: a smaller step is nothing to servoJ: the stream starts on the segment
MAX_TICKS = 5000  # 10 s at 500 Hz: a lead-in longer than that is a bug


def lead_in(q_now: FloatArray, q_start: FloatArray, period: float) -> FloatArray:
    """Servo targets (rows, one per period) from ``q_now`` at rest to ``q_start`` at rest,
    the last row exactly ``q_start``; no rows when the two are within NO_GAP."""
    n = q_start.size
    if float(np.max(np.abs(q_now - q_start))) <= NO_GAP:
        return np.zeros((0, n))
    # ruckig 0.19 raises on some gaps at the boundary between profile types (a 1-DOF move
    # of exactly 2 a^3 / j^2 from 0.2687 rad fails): then again with a lower jerk
    for scale in (1.0, 0.9, 0.8):
        try:
            return _rows(q_now, q_start, period, JERK * scale)
        except ruckig.RuckigError:
            continue
    raise RuntimeError("ruckig could not lead in from where the arms stand")


def _rows(q_now: FloatArray, q_start: FloatArray, period: float, jerk: float) -> FloatArray:
    n = q_start.size
    free = np.full(n, 1e3)  # position limits are the segment's business, not the gap's
    otg = Retargeter(
        q_now, -free, free, np.full(n, VELOCITY), np.full(n, ACCELERATION), np.full(n, jerk), period
    )
    otg.set_target(q_start)
    rows: list[FloatArray] = []
    while not otg.finished:
        if len(rows) >= MAX_TICKS:
            raise RuntimeError(f"the lead-in did not finish within {MAX_TICKS} periods")
        rows.append(otg.step()[0])
    out = np.array(rows)
    out[-1] = q_start
    return out
