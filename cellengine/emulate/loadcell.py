"""An emulated serial load cell: an Arduino with an HX711 printing one reading a line, in
grams with two decimals, ``RATE`` times a second, with Gaussian noise (seeded), for tests of
drivers/loadcell.py over a pseudo-terminal (emulate/serial_pty.py).

What it weighs is ``load`` (g), which a test harness sets (the physics the emulator does not
know: what the gripper holds). Faults: ``silence`` (it stops printing), ``garbage`` (it
prints lines that are not readings).
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field

RATE = 10.0  # readings per second


@dataclass
class LoadCellEmulator:
    load: float = 0.0  # g on the cell
    zero: float = 3.7  # g it reads with nothing on it (the tare)
    noise: float = 0.2  # g, standard deviation
    seed: int = 0
    output: bytearray = field(default_factory=bytearray)
    log: list[str] = field(default_factory=list)
    faults: tuple[str, ...] = ("silence", "garbage")
    talks_first: bool = True
    silent: bool = False
    garbage: bool = False
    _due: float = 0.0
    _random: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self._random = random.Random(self.seed)

    def receive(self, data: bytes) -> None:
        pass  # it only talks

    def advance(self, dt: float) -> None:
        self._due -= dt
        while self._due <= 0.0:
            self._due += 1.0 / RATE
            if self.silent:
                continue
            if self.garbage:
                line = "HX711 not found"
            else:
                line = f"{self.zero + self.load + self._random.gauss(0.0, self.noise):.2f}"
            self.log.append(line)
            self.output += line.encode() + b"\r\n"

    def fault(self, kind: str) -> None:
        if kind == "silence":
            self.silent = True
        elif kind == "garbage":
            self.garbage = True
        else:
            raise ValueError(f"unknown load cell fault '{kind}'; known: {', '.join(self.faults)}")
