"""The script port (TCP 30003): URScript text in. A program is ``def NAME():`` at the start
of a line up to ``end`` at the start of a line; it runs once its ``end`` has arrived (ur-rtde
sends its control script, about 42 kB, as ``def rtde_control(): ... end``). A secondary
program (``sec``) does not touch the running one; any other line outside a program is a
one-line program that replaces the running one, as on a controller. Nothing is sent back:
ur-rtde never reads this socket."""

from __future__ import annotations

import re

from cellengine.emulate.controller import Controller

_START = re.compile(r"(def|sec)\s+(\w+)\s*\(\s*\)\s*:")


class ScriptSession:
    def __init__(self, ctl: Controller) -> None:
        self.ctl = ctl
        self._buf = b""
        self._program: list[str] | None = None  # lines of the program being received
        self._kind = self._name = ""

    def received(self, data: bytes) -> None:
        self._buf += data
        while b"\n" in self._buf:
            raw, self._buf = self._buf.split(b"\n", 1)
            self._line(raw.decode("utf-8", "replace").rstrip("\r"))

    def _line(self, line: str) -> None:
        if self._program is not None:
            self._program.append(line)
            if line.rstrip() == "end":  # the program's own end: at the start of a line
                text = "\n".join(self._program) + "\n"
                self._program = None
                if self._kind == "def":
                    self.ctl.start_program(self._name, text)
                else:
                    self.ctl.log(f"secondary program '{self._name}' ignored")
            return
        start = _START.match(line)
        if start is not None:
            self._kind, self._name = start.group(1), start.group(2)
            self._program = [line]
        elif line.strip() and not line.lstrip().startswith("#"):
            self.ctl.start_program("<one line>", line)

    def closed(self) -> None:
        pass
