"""Test harness for the emulated UR controllers: the emulator in its own process (`cellengine
emulate ur`), the real ur-rtde clients in another (rtde_worker.py), and a deadline on every
wait, so a broken emulator fails a test instead of hanging it."""

from __future__ import annotations

import contextlib
import json
import os
import select
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
WORKER = Path(__file__).with_name("rtde_worker.py")


def free_hosts(n: int) -> list[str]:
    """``n`` loopback addresses whose controller ports are free, from 127.0.0.2 up (other
    emulators may be running on this machine)."""
    hosts = []
    for last in range(2, 255):
        host = f"127.0.0.{last}"
        try:
            for port in (29999, 30003, 30004):
                with socket.socket() as s:
                    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                    s.bind((host, port))
        except OSError:
            continue
        hosts.append(host)
        if len(hosts) == n:
            return hosts
    raise AssertionError("no free loopback addresses")


def wait_for(probe: Callable[[], Any], timeout: float = 5.0, what: str = "") -> Any:
    """Poll ``probe`` until it returns something true; that value."""
    deadline = time.monotonic() + timeout
    while True:
        value = probe()
        if value:
            return value
        if time.monotonic() > deadline:
            raise Hung(f"{what or probe}: still {value!r} after {timeout} s")
        time.sleep(0.002)


def rtde_packages(host: str, names: str, seconds: float) -> list[tuple[float, bytes]]:
    """A bare RTDE client: version 2, one output recipe at 500 Hz, start; then the arrival
    time and payload of every data package for ``seconds``."""
    with socket.create_connection((host, 30004), timeout=2) as s:
        buf = bytearray()

        def message(kind: str, payload: bytes = b"") -> tuple[int, bytes]:
            s.sendall(struct.pack(">HB", 3 + len(payload), ord(kind)) + payload)
            return _message(s, buf)

        assert message("V", struct.pack(">H", 2)) == (ord("V"), b"\x01")
        kind, reply = message("O", struct.pack(">d", 500.0) + names.encode())
        assert reply[0] == 1, reply
        assert message("S") == (ord("S"), b"\x01")
        out, end = [], time.monotonic() + seconds
        while time.monotonic() < end:
            kind, payload = _message(s, buf)
            if kind == ord("U"):
                out.append((time.monotonic(), payload))
        return out


def _message(s: socket.socket, buf: bytearray) -> tuple[int, bytes]:
    while len(buf) < 3 or len(buf) < struct.unpack_from(">H", buf)[0]:
        chunk = s.recv(1 << 16)
        if not chunk:
            raise Hung("RTDE: the controller closed the connection")
        buf += chunk
    size, kind = struct.unpack_from(">HB", buf)
    payload = bytes(buf[3:size])
    del buf[:size]
    return kind, payload


class Hung(AssertionError):
    """Something did not answer in time."""


class ClientError(AssertionError):
    """A client call raised (the worker reports the exception's text)."""


def _readline(fd: int, buf: bytearray, deadline: float, what: str) -> str:
    while b"\n" not in buf:
        left = deadline - time.monotonic()
        if left <= 0 or not select.select([fd], [], [], left)[0]:
            raise Hung(f"{what}: no answer in time")
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            raise Hung(f"{what}: the process ended")
        buf += chunk
    line, _, rest = bytes(buf).partition(b"\n")
    buf[:] = rest
    return line.decode()


class Emulator:
    """``cellengine emulate ur`` for ``hosts`` (with ``extra`` arguments) in a subprocess."""

    def __init__(self, hosts: list[str], *extra: str, fault_socket: bool = True) -> None:
        self.dir = tempfile.TemporaryDirectory(prefix="emulate-")
        self.socket_path = Path(self.dir.name) / "faults.sock" if fault_socket else None
        args = [sys.executable, "-m", "cellengine.cli", "emulate", "ur"]
        for host in hosts:
            args += ["--host", host]
        if self.socket_path is not None:
            args += ["--fault-socket", str(self.socket_path)]
        self.log = open(Path(self.dir.name) / "stderr.txt", "w+")  # noqa: SIM115
        self.proc = subprocess.Popen(
            [*args, *extra], cwd=ROOT, stdout=subprocess.PIPE, stderr=self.log
        )
        assert self.proc.stdout is not None
        self._buf = bytearray()
        self.ready_line = _readline(
            self.proc.stdout.fileno(), self._buf, time.monotonic() + 15, "emulator start"
        )

    def fault(self, host: str, kind: str, timeout: float = 5.0) -> str:
        """Send ``HOST KIND`` to the fault socket; the emulator's answer line."""
        assert self.socket_path is not None
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(timeout)
            s.connect(str(self.socket_path))
            s.sendall(f"{host} {kind}\n".encode())
            buf = bytearray()
            return _readline(s.fileno(), buf, time.monotonic() + timeout, "fault socket")

    def wait(self, timeout: float) -> int:
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            raise Hung(f"the emulator did not exit within {timeout} s") from None

    def terminate(self, timeout: float = 5.0) -> int:
        """SIGTERM, then the exit code."""
        self.proc.send_signal(signal.SIGTERM)
        return self.wait(timeout)

    def stderr(self) -> str:
        self.log.seek(0)
        return self.log.read()

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(5)
        assert self.proc.stdout is not None
        self.proc.stdout.close()
        self.log.close()
        self.dir.cleanup()


class Worker:
    """The real ur-rtde clients in a subprocess, one JSON request and answer at a time."""

    def __init__(self) -> None:
        read, write = os.pipe()
        self.proc = subprocess.Popen(
            [sys.executable, str(WORKER), str(write)],
            cwd=ROOT,
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,  # ur-rtde's own prints
            pass_fds=(write,),
        )
        os.close(write)
        self._fd, self._buf = read, bytearray()
        self._pending = ""

    def send(self, **req: Any) -> None:
        """Start a request; ``answer`` waits for what it returns."""
        assert self.proc.stdin is not None
        self._pending = str(req)[:120]
        try:
            self.proc.stdin.write((json.dumps(req) + "\n").encode())
            self.proc.stdin.flush()
        except BrokenPipeError:
            raise Hung(f"{self._pending}: the worker has ended") from None

    def answer(self, timeout: float = 10.0) -> dict[str, Any]:
        try:
            line = _readline(self._fd, self._buf, time.monotonic() + timeout, self._pending)
        except Hung:
            self.close()  # a client stuck in a call cannot be used again
            raise
        answer: dict[str, Any] = json.loads(line)
        return answer

    def request(self, timeout: float = 10.0, **req: Any) -> dict[str, Any]:
        self.send(**req)
        return self.answer(timeout)

    def new(self, name: str, cls: str, host: str, *args: Any, timeout: float = 10.0) -> None:
        self.check(self.request(timeout, op="new", name=name, cls=cls, host=host, args=args))

    def call(self, name: str, method: str, *args: Any, timeout: float = 10.0) -> Any:
        """The value ``name.method(*args)`` returned; ClientError if it raised."""
        req = {"op": "call", "name": name, "method": method, "args": args}
        return self.check(self.request(timeout, **req))

    def loop(self, op: str, timeout: float = 20.0, **req: Any) -> Any:
        return self.check(self.request(timeout, op=op, **req))

    @staticmethod
    def check(answer: dict[str, Any]) -> Any:
        if not answer["ok"]:
            raise ClientError(answer["error"])
        return answer["value"]

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()  # faster than the clients' disconnect (0.5 s each)
            self.proc.wait(5)
        with contextlib.suppress(OSError):
            os.close(self._fd)
        if self.proc.stdin is not None:
            with contextlib.suppress(OSError):
                self.proc.stdin.close()


def dashboard(host: str, *commands: str, timeout: float = 5.0) -> list[str]:
    """What the dashboard server at ``host`` answers to each command (as an operator would
    type them on the pendant: 'power on', 'brake release', ...)."""
    answers = []
    with socket.create_connection((host, 29999), timeout=timeout) as s:
        buf = bytearray()
        deadline = time.monotonic() + timeout
        _readline(s.fileno(), buf, deadline, "dashboard welcome")
        for command in commands:
            s.sendall(command.encode() + b"\n")
            answers.append(_readline(s.fileno(), buf, deadline, f"dashboard '{command}'"))
    return answers
