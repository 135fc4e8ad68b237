"""The GRBL 1.1 emulator's own behaviour, byte in, byte out, on a clock the test advances:
what the lab driver's client code is tested against must itself be GRBL."""

from __future__ import annotations

import pytest

from cellengine.emulate.grbl import BANNER, PLANNER_BLOCKS, RX_BUFFER, Grbl

DT = 0.001


def _answers(g: Grbl) -> list[str]:
    out = [line for line in g.output.decode().split("\r\n") if line]
    g.output.clear()
    return out


def _run(g: Grbl, until: float = 30.0) -> float:
    """Advance until idle; the time it took."""
    t = 0.0
    while g.state != "Idle" and t < until:
        g.advance(DT)
        t += DT
    return t


def _unlocked() -> Grbl:
    g = Grbl()
    g.receive(b"$X\n")
    g.output.clear()
    return g


def test_power_up_with_homing_on_is_an_alarm_until_unlocked() -> None:
    g = Grbl()
    assert bytes(g.output).startswith(BANNER) and g.state == "Alarm"
    g.output.clear()
    g.receive(b"G1X-10F600\n")
    assert _answers(g) == ["error:9"]  # G-code locked out
    g.receive(b"$X\n")
    assert _answers(g) == ["[MSG:Caution: Unlocked]", "ok"] and g.state == "Idle"


def test_homing_takes_time_and_answers_ok_when_done() -> None:
    g = Grbl()
    g.output.clear()
    g.position = [-50.0, -20.0, -10.0, 0.0]
    g.receive(b"$H\nG1X-5F600\n")
    assert _answers(g) == [] and g.state == "Home"
    while g.state == "Home":
        g.advance(DT)
    assert g.position[:3] == [0.0, 0.0, 0.0]
    assert _answers(g) == ["ok", "ok"]  # $H, then the line after it, taken in only now
    _run(g)
    assert g.position[0] == pytest.approx(-5.0, abs=1e-9)


def test_settings_and_errors() -> None:
    g = _unlocked()
    g.receive(b"$$\n")
    lines = _answers(g)
    assert lines[-1] == "ok" and "$110=6000" in lines and "$120=500" in lines
    g.receive(b"$120=250\nG1X-1\nG7\nG1X1..2F100\n")
    # a feed never set, an unsupported G code, a bad number
    assert _answers(g) == ["ok", "error:22", "error:20", "error:2"]
    assert g.settings[120] == 250.0


def test_a_move_takes_its_time_with_acceleration() -> None:
    """100 mm at F6000 (100 mm/s) with 500 mm/s^2: 0.2 s up, 0.8 s at speed, 0.2 s down."""
    g = _unlocked()
    g.receive(b"G1X-100F6000\n")
    assert _answers(g) == ["ok"]
    t = _run(g)
    assert t == pytest.approx(1.2, abs=0.01)
    assert g.position[0] == pytest.approx(-100.0, abs=1e-9)


def test_a_dwell_of_zero_and_a_move_to_where_it_is_take_no_time() -> None:
    """G4 P0 (what a host streams for a segment with nothing to move) and a G1 to the
    current position are done at once: GRBL answers and stays Idle."""
    g = _unlocked()
    g.receive(b"G4P0.000\nG1X0Y0Z0F600\n?")
    for _ in range(5):
        g.advance(DT)
    g.receive(b"?")
    answers = _answers(g)
    assert answers[:2] == ["ok", "ok"] and answers[-1].startswith("<Idle|")
    assert g.position[:3] == [0.0, 0.0, 0.0]


def test_a_target_outside_the_travel_is_a_soft_limit_alarm() -> None:
    g = _unlocked()
    g.receive(b"G1X-2000F600\n")
    assert "ALARM:2" in _answers(g) and g.state == "Alarm" and not g.planner


def test_feed_hold_stops_with_deceleration_and_cycle_start_resumes() -> None:
    g = _unlocked()
    g.receive(b"G1X-100F6000\n")
    for _ in range(500):  # at 100 mm/s after 0.5 s
        g.advance(DT)
    g.receive(b"!")
    x = g.position[0]
    t = 0.0
    while g.state != "Hold:0":
        g.advance(DT)
        t += DT
    # from 100 mm/s at 500 mm/s^2: 0.2 s and 10 mm to stop, the block kept
    assert t == pytest.approx(0.2, abs=0.01) and g.position[0] == pytest.approx(x - 10, abs=0.2)
    g.receive(b"~")
    _run(g)
    assert g.position[0] == pytest.approx(-100.0, abs=1e-9)


def test_a_reset_while_moving_loses_the_position_alarm_3() -> None:
    g = _unlocked()
    g.receive(b"G1X-100F6000\n")
    for _ in range(100):
        g.advance(DT)
    g.receive(b"\x18")
    assert "ALARM:3" in _answers(g) and g.state == "Alarm" and not g.planner


def test_the_receive_buffer_overflows_when_a_host_does_not_count() -> None:
    """15 blocks fill the planner; the lines after them wait in the 128-byte buffer, and
    what does not fit is lost."""
    g = _unlocked()
    data = b"".join(f"G1X-{k}.000F600\n".encode() for k in range(1, 41))
    g.receive(data)
    assert len(g.planner) == PLANNER_BLOCKS and len(g.rx) == RX_BUFFER
    assert g.overflows == len(data) - len(g.rx) - sum(
        len(f"G1X-{k}.000F600\n") for k in range(1, 16)
    )


def test_the_serial_emulators_name_themselves_in_usage_errors(
    capsys: pytest.CaptureFixture[str],
) -> None:
    from cellengine.cli import main

    assert main(["emulate", "dynamixel", "--fault", "0@1:bogus"]) == 2
    assert capsys.readouterr().err.strip() == (
        "cellengine emulate dynamixel: --fault '0@1:bogus': not I@T:KIND for a device I below "
        "1 and KIND one of lost, stuck, overload"
    )
    assert main(["emulate", "grbl", "--set", "3:110=1"]) == 2
    assert "cellengine emulate grbl: --set '3:110=1'" in capsys.readouterr().err
