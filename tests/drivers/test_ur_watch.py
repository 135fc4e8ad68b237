"""The UR driver's watch: safety status bits and tracking against recent commands."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.drivers.ur_watch import safety_stop, set_bits, tracking_deviation


@pytest.mark.parametrize(
    ("bits", "kind"),
    [
        (0b1, None),  # normal
        (0b11, None),  # normal + reduced
        (1 << 2, "protective_stop"),
        (1 << 4, "protective_stop"),  # safeguard stop
        (1 << 7, "emergency_stop"),
        (1 << 5 | 1 << 7, "emergency_stop"),
        (1 << 2 | 1 << 7, "emergency_stop"),  # the worse one wins
        (1 << 10, "protective_stop"),
    ],
)
def test_safety_bits_to_a_fault_kind(bits: int, kind: str | None) -> None:
    assert safety_stop(bits) == kind


def test_set_bits_are_named() -> None:
    assert set_bits(1 | 1 << 2) == ["normal", "protective stop"]


def test_a_joint_between_recent_commands_is_on_track() -> None:
    recent = np.array([[0.0, 1.0], [0.1, 1.0], [0.2, 1.0]])
    assert tracking_deviation(np.array([0.05, 1.0]), recent) == (0, 0.0)
    j, d = tracking_deviation(np.array([0.1, 1.3]), recent)
    assert j == 1 and d == pytest.approx(0.3)
    j, d = tracking_deviation(np.array([-0.05, 1.0]), recent)
    assert j == 0 and d == pytest.approx(0.05)
