"""The lab gripper client (ROBOTIS' dynamixel-sdk, Protocol 2.0) against the emulated
Dynamixel bus on a pseudo-terminal: ping, a mode reached, a grasp confirmed by the servo
stopping short with load, and the failures a real gripper has."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from cellengine.drivers.dynamixel_grip import Gripper, GripperError
from cellengine.emulate.dynamixel import MODEL_XM430, DynamixelBus, Servo, crc16, packet
from cellengine.emulate.serial_pty import Port
from tests.drivers.ptys import served

POSITIONS = {"open": 2600, "grasp": 1500, "slide": 2200}


@pytest.fixture
def bus() -> Iterator[Port]:
    with served(DynamixelBus({1: Servo(1), 2: Servo(2)})) as (p,):
        yield p


def _settle(g: Gripper) -> None:
    deadline = time.monotonic() + 5.0
    while not g.settled():
        assert time.monotonic() < deadline
        time.sleep(0.01)


def test_the_crc_and_a_packet_as_the_protocol_documents() -> None:
    # ROBOTIS' e-manual, Protocol 2.0, "Ping" example: ID 1, CRC 0x4E19
    assert packet(1, 0x01, b"") == bytes.fromhex("FFFFFD0001030001194E")
    assert crc16(bytes.fromhex("FFFFFD0001030001")) == 0x4E19
    # the header in a parameter is stuffed
    assert b"\xff\xff\xfd\xfd" in packet(1, 0x03, b"\x74\x00\xff\xff\xfd")


def test_modes_are_reached_and_a_grasp_is_confirmed_by_load(bus: Port) -> None:
    g = Gripper(bus.path, 1, POSITIONS, timeout=2.0)
    g.open()
    g.set("open", holds=False)
    _settle(g)
    bus.device.servos[1].stop = 1800.0  # a 28 mm vial between the fingers
    g.set("grasp", holds=True)
    _settle(g)
    assert abs(bus.device.servos[1].position - 1800.0) < 1.0
    g.close()


def test_a_grasp_on_nothing_and_a_stuck_servo_are_errors(bus: Port) -> None:
    # a second: four times what the fingers take to close (548 ticks at 2000 ticks/s), so a
    # loaded machine does not read a slow close as a failed one
    g = Gripper(bus.path, 2, POSITIONS, timeout=1.0)
    g.open()
    g.set("grasp", holds=True)  # nothing between the fingers: it reaches its goal
    with pytest.raises(GripperError, match=r"jaw mode 'grasp' closed on nothing"):
        _settle(g)
    bus.device.fault("stuck")
    g.set("open", holds=False)
    with pytest.raises(GripperError, match=r"jaw mode 'open' did not reach it"):
        _settle(g)
    bus.device.fault("overload")
    with pytest.raises(GripperError, match=r"hardware error status 0x20"):
        g.settled()


def test_a_servo_that_is_not_there_does_not_answer(bus: Port) -> None:
    g = Gripper(bus.path, 7, POSITIONS)
    with pytest.raises(GripperError, match=r"id 7: ping: \[TxRxResult\] There is no status packet"):
        g.open()


def test_an_xm430_squeezes_with_each_modes_current_and_confirms_by_it() -> None:
    """``model: xm430`` with ``currents``: current-based position control, each mode's goal
    current written before its position, a grasp confirmed by pressing with that current."""
    servos = {3: Servo(3, model=MODEL_XM430), 4: Servo(4)}
    with served(DynamixelBus(servos)) as (p,):
        g = Gripper(p.path, 3, POSITIONS, model="xm430", currents={"grasp": 300.0, "open": 500.0})
        g.open()
        assert servos[3].word(11, 1) == 5  # current-based position control
        servos[3].stop = 1800.0
        g.set("grasp", holds=True)
        _settle(g)
        assert servos[3].word(102, 2) == round(300.0 / 2.69)
        servos[3].stop = None  # the vial let go
        g.set("open", holds=False)
        _settle(g)
        assert servos[3].word(102, 2) == round(500.0 / 2.69)
        xl = Gripper(p.path, 4, POSITIONS, model="xm430", bus=g.bus)
        with pytest.raises(
            GripperError, match=r"id 4: model number 1060, not the cell file's xm430"
        ):
            xl.open()
        g.close()
