"""The driver's end of one arm's process (ur_arm.py, the arm's ur-rtde clients).

Every request has a deadline. An arm whose process crashed, hung past a deadline, or lost
its controller becomes a LinkError with ``lost`` set: its process is killed (which closes
its connections; the controller's watchdog stops the arm) and nothing more is asked of it.
Neither a crash nor a hang in the vendor library can reach the driver's process.
"""

from __future__ import annotations

import contextlib
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Mapping
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, NoReturn

PROGRAM = Path(__file__).with_name("ur_arm.py")
REAP_TIMEOUT = 1.0  # s for an ended or killed process to be reaped
DRAIN_TIMEOUT = 1.0  # s for the answer to a request whose caller was interrupted


class LinkError(Exception):
    """A request to arm ``arm`` failed: ``lost`` when its process is gone for good, else
    the vendor library's error (the process still serves)."""

    def __init__(self, arm: str, why: str, lost: bool) -> None:
        super().__init__(why)
        self.arm, self.why, self.lost = arm, why, lost


class ArmLink:
    """The process serving arm ``arm``'s controller at ``ip``, started at once."""

    def __init__(self, arm: str, ip: str) -> None:
        self.arm, self.ip = arm, ip
        ours, theirs = socket.socketpair()
        # -I: the standard library and site-packages only (not this folder, no PYTHON*)
        command = [sys.executable, "-I", str(PROGRAM), str(theirs.fileno()), ip]
        self.process = subprocess.Popen(
            command, pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL
        )
        theirs.close()
        self._conn = Connection(ours.detach())
        self.lost: str | None = None  # why the link is gone for good
        self._pending = 0  # requests sent and not answered (an interrupted exchange)

    @property
    def live(self) -> bool:
        return self.lost is None

    def call(self, op: str, *args: Any, timeout: float) -> Any:
        self.send(op, *args)
        return self.receive(timeout)

    def send(self, op: str, *args: Any) -> None:
        while self._pending:  # the answers no one waited for: dropped, in order
            with contextlib.suppress(LinkError):
                self.receive(DRAIN_TIMEOUT)
        if self.lost is not None:
            raise LinkError(self.arm, self.lost, True)
        try:
            self._pending += 1
            self._conn.send((op, *args))
        except OSError:
            self._lose(self._ended())

    def receive(self, timeout: float) -> Any:
        """The answer to the request sent last; LinkError when it failed or did not come
        within ``timeout`` (s)."""
        if self.lost is not None:
            raise LinkError(self.arm, self.lost, True)
        try:
            if not self._conn.poll(timeout):
                self._lose(f"no answer within {timeout:g} s")
            kind, value = self._conn.recv()
            self._pending -= 1
        except (EOFError, OSError):
            self._lose(self._ended())
        if kind == "ok":
            return value
        if kind == "lost":
            self._lose(str(value))
        raise LinkError(self.arm, str(value), False)

    def close(self, timeout: float) -> None:
        """End the process: ``timeout`` (s) to end by itself (after a ``disconnect``),
        else killed."""
        if self.lost is None:
            self.lost = "closed"
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.process.wait(timeout)
        self._kill()

    def _lose(self, why: str) -> NoReturn:
        self.lost, self._pending = why, 0
        self._kill()
        raise LinkError(self.arm, why, True)

    def _ended(self) -> str:
        try:
            code = self.process.wait(REAP_TIMEOUT)
        except subprocess.TimeoutExpired:
            return "its process stopped answering"
        if code < 0:
            return f"its process crashed ({signal.Signals(-code).name})"
        return f"its process ended (exit code {code})"

    def _kill(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait(REAP_TIMEOUT)
        self._conn.close()


def exchange(
    links: Mapping[str, ArmLink], requests: Mapping[str, tuple[Any, ...]], timeout: float
) -> dict[str, Any]:
    """Each arm's request ``(op, *args)`` sent to its link at once, then every answer within
    ``timeout`` (s) of the sending: per arm its value, or the LinkError."""
    out: dict[str, Any] = {}
    for arm, (op, *args) in requests.items():
        try:
            links[arm].send(op, *args)
        except LinkError as e:
            out[arm] = e
    end = time.perf_counter() + timeout
    for arm in requests:
        if arm not in out:
            try:
                out[arm] = links[arm].receive(max(0.0, end - time.perf_counter()))
            except LinkError as e:
                out[arm] = e
    return out
