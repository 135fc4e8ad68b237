"""RTDE framing (protocol version 2): a big-endian ``uint16`` size (header included) and a
``uint8`` type, then the payload. Recipes turn variable names into one struct each."""

from __future__ import annotations

import struct
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field

from cellengine.emulate.rtde_types import FORMATS

REQUEST_PROTOCOL_VERSION = ord("V")
GET_URCONTROL_VERSION = ord("v")
TEXT_MESSAGE = ord("M")
DATA_PACKAGE = ord("U")
SETUP_OUTPUTS = ord("O")
SETUP_INPUTS = ord("I")
START = ord("S")
PAUSE = ord("P")

HEADER = struct.Struct(">HB")
MAX_MESSAGE = 0xFFFF

Value = float | int | bool | tuple[float, ...] | tuple[int, ...]


def frame(kind: int, payload: bytes = b"") -> bytes:
    """One message: header and payload."""
    return HEADER.pack(HEADER.size + len(payload), kind) + payload


class Deframer:
    """Cuts a byte stream into (type, payload) messages."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> Iterator[tuple[int, bytes]]:
        self._buf += data
        while len(self._buf) >= HEADER.size:
            size, kind = HEADER.unpack_from(self._buf)
            if size < HEADER.size:
                raise ValueError(f"RTDE message size {size} is smaller than its header")
            if len(self._buf) < size:
                return
            payload = bytes(self._buf[HEADER.size : size])
            del self._buf[:size]
            yield kind, payload


def names(text: bytes) -> list[str]:
    """The variable names of a setup request: comma separated, ur-rtde ends with a comma."""
    return [n.strip() for n in text.decode("utf-8", "replace").split(",") if n.strip()]


@dataclass
class Recipe:
    """An output or input recipe: its id, the variables by name and their wire types."""

    id: int
    names: list[str]
    types: list[str]
    period_ticks: int = 1  # outputs: one package every this many 2 ms ticks
    _struct: struct.Struct = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._struct = struct.Struct(">B" + "".join(FORMATS[t] for t in self.types))

    def pack(self, values: Sequence[Value]) -> bytes:
        flat: list[float | int | bool] = [self.id]
        for v in values:
            if isinstance(v, tuple):
                flat.extend(v)
            else:
                flat.append(v)
        return frame(DATA_PACKAGE, self._struct.pack(*flat))

    def unpack(self, payload: bytes) -> dict[str, Value]:
        """The values of an input package (its first byte, the recipe id, included)."""
        flat = self._struct.unpack(payload)[1:]
        out: dict[str, Value] = {}
        i = 0
        for name, t in zip(self.names, self.types, strict=True):
            n = int(FORMATS[t][:-1]) if len(FORMATS[t]) > 1 else 1
            out[name] = tuple(flat[i : i + n]) if n > 1 else flat[i]
            i += n
        return out

    @property
    def size(self) -> int:
        return self._struct.size
