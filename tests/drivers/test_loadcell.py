"""The serial load cell client against the emulated HX711 on a pseudo-terminal: tare,
the median of fresh readings, and garbage, silence and a lost port as clear errors."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from cellengine.drivers.loadcell import LoadCell, LoadCellError
from cellengine.emulate.loadcell import LoadCellEmulator
from cellengine.emulate.serial_pty import Port
from tests.drivers.ptys import served


@pytest.fixture
def port() -> Iterator[Port]:
    with served(LoadCellEmulator(zero=3.7, noise=0.2, seed=1)) as (p,):
        yield p


def test_tare_then_weigh_a_vial(port: Port) -> None:
    cell = LoadCell(port.path, readings=5, settle=0.0, timeout=1.0)
    cell.open()
    assert cell.zero() == pytest.approx(0.0037, abs=0.0005)
    port.device.load = 42.0  # a 42 g vial in the gripper
    assert cell.weigh() == pytest.approx(0.042, abs=0.0005)
    cell.close()


def test_garbage_silence_and_a_lost_port_are_errors(port: Port) -> None:
    cell = LoadCell(port.path, readings=3, settle=0.0, timeout=0.5)
    cell.open()
    port.device.fault("garbage")
    with pytest.raises(LoadCellError, match="'HX711 not found' is not a reading"):
        cell.weigh()
    port.device.garbage = False
    port.device.fault("silence")
    with pytest.raises(LoadCellError, match=r"no reading within 0.5 s \(is the load cell on\?\)"):
        cell.weigh()
    port.faults.append((0.0, "lost"))
    with pytest.raises(LoadCellError, match="the port went away"):
        for _ in range(20):
            cell.weigh()
