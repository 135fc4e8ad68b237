"""Non-blocking TCP connections for the single-threaded emulator: each passes what it reads
to its session and queues what it cannot send at once; the loop flushes the queues every
tick. A client that stops reading is dropped, as a controller drops one whose buffer
overflows."""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Callable
from typing import Protocol

MAX_PENDING = 2 << 20  # bytes queued for one client (about 3 s of RTDE at 500 Hz)


class Session(Protocol):
    def received(self, data: bytes) -> None: ...

    def closed(self) -> None: ...


class Conn:
    """One accepted connection and its session."""

    def __init__(self, sock: socket.socket, on_close: Callable[[Conn], None]) -> None:
        sock.setblocking(False)
        with contextlib.suppress(OSError):  # not for Unix sockets
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.sock, self._on_close = sock, on_close
        self.pending = bytearray()
        self.open = True
        self.session: Session | None = None

    def send(self, data: bytes) -> None:
        if not self.open:
            return
        self.pending += data
        self.flush()
        if len(self.pending) > MAX_PENDING:
            self.close()

    def flush(self) -> None:
        while self.open and self.pending:
            try:
                n = self.sock.send(self.pending)
            except BlockingIOError:
                return
            except OSError:
                self.close()
                return
            del self.pending[:n]

    def readable(self) -> None:
        try:
            data = self.sock.recv(1 << 16)
        except BlockingIOError:
            return
        except OSError:
            data = b""
        if not data:
            self.close()
        elif self.session is not None:
            self.session.received(data)

    def close(self) -> None:
        if self.open:
            self.open = False
            with contextlib.suppress(OSError):
                self.sock.close()
            if self.session is not None:
                self.session.closed()
            self._on_close(self)


def listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (any 127.x.y.z address works on Linux)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((host, port))
    except OSError:
        sock.close()
        raise
    sock.listen(8)
    sock.setblocking(False)
    return sock
