"""One UR arm's ur-rtde clients in a process of their own: the program ur_link.ArmLink runs.

ur-rtde's clients can crash or hang their process when their controller goes away (a
segfault while the control client reconnects, a stopJ that never returns, a destructor that
throws). Here that costs only this process: the driver sees its link end or time out, and
stops the other arm.

It serves requests ``(op, *args)`` from the socket given on the command line, one at a time,
and answers each with ``("ok", value)``, ``("error", text)`` or ``("lost", text)`` (a
connection is down: nothing more is asked of any client, as a call on it would block
reconnecting). While idle it kicks the RTDE watchdog (after ``watchdog``, until ``servo`` or
``stop``), so that the watchdog fires only when the driver's process is gone or stuck
streaming. When the driver's end of the socket closes, it exits at once: closing the
connections and letting the controller's watchdog stop the arm.

Run as a script (not ``-m``) so that it imports the standard library and ur-rtde only.
"""

from __future__ import annotations

import os
import signal
import sys
import time
from multiprocessing.connection import Connection
from typing import Any

KICK_PERIOD = 0.02  # s between idle kicks, five within the watchdog's 0.1 s

State = tuple[list[float], list[float], int]  # actual q, actual qd, safety status bits


class Lost(Exception):
    """A connection to the controller is down."""


class Arm:
    """The clients of the controller at ``ip``; each method is one request's op."""

    def __init__(self, ip: str) -> None:
        self.ip = ip
        self.rcv: Any = None
        self.ctl: Any = None
        self.io: Any = None
        self.kicking = False

    def model(self) -> str:
        import dashboard_client

        client = dashboard_client.DashboardClient(self.ip)
        client.connect()
        model = str(client.getRobotModel()).strip()
        client.disconnect()
        return model

    def connect_receive(self) -> tuple[int, int, int]:
        """Robot mode, safety mode and safety status bits."""
        import rtde_receive

        self.rcv = rtde_receive.RTDEReceiveInterface(self.ip)
        rcv = self.rcv
        return int(rcv.getRobotMode()), int(rcv.getSafetyMode()), int(rcv.getSafetyStatusBits())

    def connect_control(self) -> None:
        import rtde_control

        self.ctl = rtde_control.RTDEControlInterface(self.ip)

    def connect_io(self) -> None:
        import rtde_io

        self.io = rtde_io.RTDEIOInterface(self.ip)

    def watchdog(self, hz: float) -> bool:
        self._check()
        self.kicking = bool(self.ctl.setWatchdog(hz))
        return self.kicking

    def idle(self, on: bool) -> None:
        self.kicking = on

    def kick(self) -> None:
        self._check()
        self.ctl.kickWatchdog()

    def servo(self, q: list[float], period: float, lookahead: float, gain: float) -> State:
        """servoJ to ``q`` (servoJ feeds the watchdog itself: no kicks while streaming),
        then the arm's state."""
        self.kicking = False
        self._check()
        self.ctl.servoJ(q, 0.0, 0.0, period, lookahead, gain)
        return self.read()

    def read(self) -> State:
        self._check()
        rcv = self.rcv
        return list(rcv.getActualQ()), list(rcv.getActualQd()), int(rcv.getSafetyStatusBits())

    def stop(self, deceleration: float) -> None:
        """An asynchronous stopJ: returns when it is sent."""
        self.kicking = False
        self._check()
        self.ctl.stopJ(deceleration, True)

    def servo_stop(self, deceleration: float, idle_after: bool) -> None:
        """servoStop, which returns when the arm stands; idle kicks again if ``idle_after``."""
        self._check()
        self.ctl.servoStop(deceleration)
        self.kicking = idle_after

    def dout(self, outputs: list[tuple[int, bool]]) -> int | None:
        """Set the standard digital outputs in the order given (ur-rtde sets one per call:
        a change of two pins passes through a state with one); the first output the
        controller refused, or None."""
        self._check()
        for pin, high in outputs:
            if not self.io.setStandardDigitalOut(pin, high):
                return pin
        return None

    def disconnect(self) -> None:
        self.kicking = False
        for client in (self.io, self.ctl, self.rcv):
            if client is not None and client.isConnected():
                client.disconnect()

    def _check(self) -> None:
        """Lost unless every connection is up (the receive client often sees a drop before
        the control client's flag does)."""
        if self.rcv is None or self.ctl is None:
            raise RuntimeError(f"not connected to {self.ip} yet")
        for name, client in (("receive", self.rcv), ("control", self.ctl), ("IO", self.io)):
            if client is not None and not client.isConnected():
                raise Lost(f"the RTDE {name} connection to {self.ip} is down")


def serve(conn: Connection, arm: Arm) -> None:
    """Answer requests until the driver says ``disconnect``, a connection is lost, or the
    driver's end closes."""
    due = 0.0  # when the next idle kick is due (time.monotonic), however busy the link
    while True:
        if arm.kicking:
            now = time.monotonic()
            if now >= due:
                try:
                    arm.kick()
                except Exception:  # the watchdog stops the arm; the next request says why
                    arm.kicking = False
                due = now + KICK_PERIOD
                continue
            if not conn.poll(due - now):
                continue
        try:
            op, *args = conn.recv()
        except (EOFError, OSError):
            return
        try:
            reply: tuple[str, Any] = ("ok", getattr(arm, op)(*args))
        except Lost as e:
            conn.send(("lost", str(e)))
            return
        except Exception as e:
            reply = ("error", str(e) or type(e).__name__)
        conn.send(reply)
        if op == "disconnect":
            return


def main(argv: list[str]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the driver's to handle
    fd, ip = int(argv[1]), argv[2]
    try:
        serve(Connection(fd), Arm(ip))
    finally:
        # no interpreter teardown: ur-rtde's client threads and destructors can crash it
        sys.stdout.flush()
        os._exit(0)


if __name__ == "__main__":
    main(sys.argv)
