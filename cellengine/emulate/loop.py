"""The emulator's one thread: a selector over every socket and a 2 ms tick. Each tick steps
every controller (program, watchdog, arm) and sends the data packages due; a late tick is
caught up by stepping again, and only the latest packages are sent, as a controller short
of time skips packages."""

from __future__ import annotations

import contextlib
import functools
import os
import selectors
import signal
import socket
import sys
import time
import traceback
from collections.abc import Callable
from pathlib import Path

from cellengine.emulate.arm import DT
from cellengine.emulate.controller import Controller
from cellengine.emulate.dashboard_server import DashboardSession
from cellengine.emulate.faults import Fault, FaultSession
from cellengine.emulate.net import Conn, listen
from cellengine.emulate.rtde_server import RtdeSession
from cellengine.emulate.script_server import ScriptSession

DASHBOARD, SCRIPT, RTDE = 29999, 30003, 30004
MAX_CATCH_UP = 50  # ticks stepped at once after a stall; beyond that the clock jumps


class Emulator:
    def __init__(
        self, controllers: list[Controller], faults: list[Fault], fault_socket: Path | None
    ) -> None:
        self.controllers = {c.host: c for c in controllers}
        self.scheduled = sorted(faults, key=lambda f: f.at or 0.0)
        self.fault_socket = fault_socket
        self.sel = selectors.DefaultSelector()
        self.listeners: dict[str, list[socket.socket]] = {h: [] for h in self.controllers}
        self.conns: dict[str, list[Conn]] = {h: [] for h in self.controllers}
        self.claims: dict[str, dict[str, RtdeSession]] = {h: {} for h in self.controllers}
        self.fault_conns: list[Conn] = []
        self.fault_listener: socket.socket | None = None
        self.tick = 0
        self.first_start: int | None = None  # tick of the first RTDE start
        self.late_ticks = 0
        self.sent = dict.fromkeys(self.controllers, 0)  # data packages per controller
        self.started_at = time.monotonic()
        self.stopping = False
        self.kill_now = False

    # -- sockets ------------------------------------------------------------------------

    def _watch(self, sock: socket.socket, callback: Callable[[], None]) -> None:
        self.sel.register(sock, selectors.EVENT_READ, callback)

    def _forget(self, sock: socket.socket) -> None:
        with contextlib.suppress(KeyError, ValueError):
            self.sel.unregister(sock)

    def open_listeners(self, host: str) -> None:
        opened: list[socket.socket] = []
        try:
            for port in (DASHBOARD, SCRIPT, RTDE):
                opened.append(listen(host, port))
        except OSError:
            for sock in opened:
                sock.close()
            raise
        for sock, port in zip(opened, (DASHBOARD, SCRIPT, RTDE), strict=True):
            self.listeners[host].append(sock)
            self._watch(sock, functools.partial(self._accept, host, sock, port))

    def _accept(self, host: str, listener: socket.socket, port: int) -> None:
        try:
            sock, _ = listener.accept()
        except OSError:
            return
        ctl = self.controllers[host]
        conn = Conn(sock, lambda c: self._closed(host, c))
        if port == DASHBOARD:
            conn.session = DashboardSession(ctl, conn)
        elif port == SCRIPT:
            conn.session = ScriptSession(ctl)
        else:
            conn.session = RtdeSession(ctl, conn, self.claims[host])
        self.conns[host].append(conn)
        self._watch(sock, conn.readable)

    def _closed(self, host: str, conn: Conn) -> None:
        self._forget(conn.sock)
        with contextlib.suppress(ValueError):
            self.conns[host].remove(conn)

    def open_fault_socket(self, path: Path) -> None:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.bind(str(path))
        sock.listen(4)
        sock.setblocking(False)
        self.fault_listener = sock
        self._watch(sock, functools.partial(self._accept_fault, sock))

    def _accept_fault(self, listener: socket.socket) -> None:
        try:
            sock, _ = listener.accept()
        except OSError:
            return
        conn = Conn(sock, self._fault_closed)
        conn.session = FaultSession(conn, self.apply)
        self.fault_conns.append(conn)
        self._watch(sock, conn.readable)

    def _fault_closed(self, conn: Conn) -> None:
        self._forget(conn.sock)
        with contextlib.suppress(ValueError):
            self.fault_conns.remove(conn)

    # -- faults -------------------------------------------------------------------------

    def apply(self, fault: Fault) -> str | None:
        """Inject a fault now; an error message if it cannot be."""
        ctl = self.controllers.get(fault.host)
        if ctl is None:
            return f"no emulated controller at '{fault.host}'; known: {', '.join(self.controllers)}"
        ctl.log(f"fault '{fault.kind}' injected at tick {ctl.tick_count}")
        if fault.kind == "protective_stop":
            ctl.protective_stop("injected")
        elif fault.kind == "emergency_stop":
            ctl.emergency_stop("injected")
        elif fault.kind == "frozen":
            ctl.arm.frozen = True
        elif fault.kind == "drop":
            for sock in self.listeners[fault.host]:
                self._forget(sock)
                sock.close()
            self.listeners[fault.host] = []
            for conn in list(self.conns[fault.host]):
                conn.close()
        elif fault.kind == "kill":
            self.kill_now = True
        else:  # clear
            ctl.clear()
            if not self.listeners[fault.host]:
                try:
                    self.open_listeners(fault.host)
                except OSError as e:
                    return f"cannot listen on {fault.host} again: {e}"
        return None

    def _due_faults(self) -> None:
        if self.first_start is None:
            return
        elapsed = (self.tick - self.first_start) * DT
        while self.scheduled and (self.scheduled[0].at or 0.0) <= elapsed + 1e-9:
            self.apply(self.scheduled.pop(0))

    # -- the loop -----------------------------------------------------------------------

    def _step(self) -> None:
        self.tick += 1
        for ctl in self.controllers.values():
            ctl.tick()
        if self.first_start is None and any(
            isinstance(c.session, RtdeSession) and c.session.started
            for conns in self.conns.values()
            for c in conns
        ):
            self.first_start = self.tick
        self._due_faults()

    def run(self, ready: Callable[[], None]) -> int:
        for sig in (signal.SIGTERM, signal.SIGINT):
            signal.signal(sig, lambda *_: setattr(self, "stopping", True))
        for host in self.controllers:
            self.open_listeners(host)
        if self.fault_socket is not None:
            self.open_fault_socket(self.fault_socket)
        ready()
        next_tick = time.monotonic() + DT
        while not self.stopping:
            for key, _ in self.sel.select(max(0.0, next_tick - time.monotonic())):
                self._event(key.data)
            if self.kill_now:
                self._flush_all()
                os.kill(os.getpid(), signal.SIGKILL)
            now = time.monotonic()
            if now < next_tick:
                continue
            due = int((now - next_tick) / DT) + 1
            self.late_ticks += due - 1
            for _ in range(min(due, MAX_CATCH_UP)):
                self._step()
            next_tick += due * DT
            for host, conns in self.conns.items():
                for conn in list(conns):
                    if isinstance(conn.session, RtdeSession):
                        self.sent[host] += conn.session.publish(self.tick)
                    conn.flush()
        self.close()
        seconds = time.monotonic() - self.started_at
        for host, n in self.sent.items():
            log(f"{host}: {n} data packages in {seconds:.1f} s")
        log(f"stopped after {self.tick} ticks, {self.late_ticks} of them caught up late")
        return 0

    def _event(self, callback: Callable[[], None]) -> None:
        try:
            callback()
        except Exception:  # a bug in one session must not take every controller down
            log("internal error, connection closed:\n" + traceback.format_exc())
            conn = getattr(callback, "__self__", None)
            if isinstance(conn, Conn):
                conn.close()

    def _flush_all(self) -> None:
        for conns in [*self.conns.values(), self.fault_conns]:
            for conn in conns:
                conn.flush()

    def close(self) -> None:
        for conns in [*self.conns.values(), self.fault_conns]:
            for conn in list(conns):
                conn.close()
        for sock in [*(s for socks in self.listeners.values() for s in socks), self.fault_listener]:
            if sock is not None:
                self._forget(sock)
                sock.close()
        if self.fault_socket is not None:
            with contextlib.suppress(FileNotFoundError):
                self.fault_socket.unlink()
        self.sel.close()


def log(message: str) -> None:
    print(f"cellengine emulate: {message}", file=sys.stderr, flush=True)
