"""The lead-in from where the arms stand to a segment's first point (ruckig)."""

import numpy as np

from cellengine.drivers.lead_in import ACCELERATION, VELOCITY, lead_in

PERIOD = 0.002


def test_no_gap_no_lead_in() -> None:
    q = np.linspace(-1, 1, 12)
    assert lead_in(q + 4e-4, q, PERIOD).shape == (0, 12)


def test_a_gap_is_closed_smoothly_within_the_limits() -> None:
    q_start = np.linspace(-1, 1, 12)
    q_now = q_start.copy()
    q_now[[2, 7]] += [0.01, -0.004]
    rows = lead_in(q_now, q_start, PERIOD)
    assert np.array_equal(rows[-1], q_start)
    path = np.vstack([q_now, rows])
    qd = np.diff(path, axis=0) / PERIOD
    qdd = np.diff(qd, axis=0) / PERIOD
    assert np.max(np.abs(qd)) <= VELOCITY + 1e-9
    assert np.max(np.abs(qdd)) <= ACCELERATION * 1.01
    # the first step is small: no jump onto the segment
    assert np.max(np.abs(rows[0] - q_now)) < 1e-5
    # the joints that do not move stay put
    assert np.allclose(rows[:, 0], q_start[0])
    # a 0.01 rad gap takes a few tenths of a second at most
    assert len(rows) * PERIOD < 0.3
