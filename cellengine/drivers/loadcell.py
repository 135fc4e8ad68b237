"""A serial load cell: an Arduino printing one plain-text reading per line (10 Hz is usual:
an HX711 sketch), e.g. ``12.34`` or ``12.34 g``, in the cell file's unit.

A weighing is the median of ``readings`` consecutive readings once ``settle`` s have passed
(the arm has just stopped), less the tare (the median read with the gripper empty when the
driver activates). A line that is not a number, readings that do not come (``timeout``), or
a port that goes away are faults, with what was read.
"""

from __future__ import annotations

import re
import statistics
import time
from typing import Any

UNITS = {"g": 1e-3, "kg": 1.0, "mg": 1e-6}  # to kg
READING = re.compile(r"\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(mg|g|kg)?\s*")


class LoadCellError(RuntimeError):
    """No usable reading: garbage, silence, a lost port."""


class LoadCell:
    def __init__(
        self,
        port: str,
        baud: int = 9600,
        unit: str = "g",
        readings: int = 5,
        settle: float = 0.5,
        timeout: float = 2.0,
        serial: Any = None,
    ) -> None:
        if unit not in UNITS:
            raise ValueError(f"unknown unit '{unit}'; known: {', '.join(UNITS)}")
        self.port, self.baud, self.unit = port, baud, unit
        self.readings, self.settle, self.timeout = readings, settle, timeout
        self.serial = serial
        self.tare = 0.0  # kg
        self._partial = b""

    def open(self) -> None:
        if self.serial is None:
            import serial

            try:
                self.serial = serial.Serial(self.port, self.baud, timeout=0)
            except (serial.SerialException, OSError) as e:
                raise LoadCellError(f"cannot open {self.port}: {e}") from None

    def close(self) -> None:
        if self.serial is not None:
            self.serial.close()

    def zero(self) -> float:
        """Tare: what it reads now (nothing held) becomes zero; that reading (kg)."""
        self.tare = 0.0
        self.tare = self.weigh(settle=0.0)
        return self.tare

    def weigh(self, settle: float | None = None) -> float:
        """The median of ``readings`` fresh readings after ``settle`` s, less the tare (kg)."""
        wait = self.settle if settle is None else settle
        if wait > 0:
            time.sleep(wait)
        self._drain()  # readings taken while the arm moved are not this weighing's
        values = [self._next() for _ in range(self.readings)]
        return statistics.median(values) - self.tare

    def _drain(self) -> None:
        assert self.serial is not None
        self._partial = b""
        try:
            while self.serial.read(4096):
                pass
        except Exception as e:
            raise LoadCellError(f"{self.port}: the port went away ({e})") from None
        # the next line may be cut at its start: read up to its end and drop it
        self._line(first=True)

    def _next(self) -> float:
        line = self._line()
        m = READING.fullmatch(line)
        if m is None:
            raise LoadCellError(f"{self.port}: '{line[:40]}' is not a reading (a number, g/kg)")
        return float(m[1]) * UNITS[m[2] or self.unit]

    def _line(self, first: bool = False) -> str:
        assert self.serial is not None
        deadline = time.monotonic() + self.timeout
        while b"\n" not in self._partial:
            try:
                data = self.serial.read(4096)
            except Exception as e:
                raise LoadCellError(f"{self.port}: the port went away ({e})") from None
            if data:
                self._partial += data
                continue
            if time.monotonic() > deadline:
                raise LoadCellError(
                    f"{self.port}: no reading within {self.timeout:g} s (is the load cell on?)"
                )
            time.sleep(0.005)
        raw, _, self._partial = self._partial.partition(b"\n")
        return "" if first else raw.decode("ascii", errors="replace").strip()
