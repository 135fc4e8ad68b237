"""One RTDE client session (TCP 30004, protocol version 2).

V (protocol version) -> accepted if 2; v -> the controller's version; O (output setup:
frequency and names) and I (input setup: names) -> a recipe id and the types, recipes
parsed by name: an unknown name is NOT_FOUND (input recipe id 0), an input another client
holds is IN_USE; S / P start and pause the data packages; U (an input package) updates the
controller's inputs, started or not (ur-rtde's IO interface never sends S). Output recipe
ids and input recipe ids count from 1 separately, in the order they were set up.
"""

from __future__ import annotations

import struct

from cellengine.emulate import rtde_protocol as rp
from cellengine.emulate.arm import DT
from cellengine.emulate.controller import VERSION, Controller
from cellengine.emulate.net import Conn
from cellengine.emulate.rtde_types import input_type, output_type

PROTOCOL_VERSION = 2


class RtdeSession:
    def __init__(self, ctl: Controller, conn: Conn, claims: dict[str, RtdeSession]) -> None:
        self.ctl, self.conn = ctl, conn
        self.claims = claims  # input variable -> the session that writes it (per controller)
        self.outputs: list[rp.Recipe] = []
        self.inputs: dict[int, rp.Recipe] = {}
        self.started = False
        self.sent = 0
        self._next_input_id = 1
        self._due: dict[int, int] = {}  # output recipe id -> tick of its next package
        self._deframer = rp.Deframer()

    def received(self, data: bytes) -> None:
        try:
            for kind, payload in self._deframer.feed(data):
                self._handle(kind, payload)
        except (ValueError, struct.error, IndexError) as e:
            self.ctl.log(f"RTDE: malformed message ({e}): connection closed")
            self.conn.close()

    def _handle(self, kind: int, payload: bytes) -> None:
        if kind == rp.REQUEST_PROTOCOL_VERSION:
            (version,) = struct.unpack(">H", payload[:2])
            self.conn.send(rp.frame(kind, bytes([version == PROTOCOL_VERSION])))
        elif kind == rp.GET_URCONTROL_VERSION:
            self.conn.send(rp.frame(kind, struct.pack(">IIII", *VERSION)))
        elif kind == rp.SETUP_OUTPUTS:
            self._setup_outputs(payload)
        elif kind == rp.SETUP_INPUTS:
            self._setup_inputs(payload)
        elif kind in (rp.START, rp.PAUSE):
            self.started = kind == rp.START
            self._due.clear()
            self.conn.send(rp.frame(kind, b"\x01"))
        elif kind == rp.DATA_PACKAGE:
            recipe = self.inputs.get(payload[0])
            if recipe is None or len(payload) != recipe.size:
                self.ctl.log(f"RTDE: input package for unknown recipe {payload[0]} ignored")
            else:
                self.ctl.write_inputs(recipe.unpack(payload))
        # text messages (M) from a client are only logged by a controller

    def _setup_outputs(self, payload: bytes) -> None:
        (frequency,) = struct.unpack(">d", payload[:8])
        names = rp.names(payload[8:])
        types = [output_type(n) or "NOT_FOUND" for n in names]
        if "NOT_FOUND" in types or not names:
            self.conn.send(rp.frame(rp.SETUP_OUTPUTS, b"\x00" + ",".join(types).encode()))
            return
        period = max(1, round(1.0 / (DT * frequency))) if frequency > 0 else 1
        recipe = rp.Recipe(len(self.outputs) + 1, names, types, period)
        self.outputs.append(recipe)
        self.conn.send(rp.frame(rp.SETUP_OUTPUTS, bytes([recipe.id]) + ",".join(types).encode()))

    def _setup_inputs(self, payload: bytes) -> None:
        names = rp.names(payload)
        types = [input_type(n) or "NOT_FOUND" for n in names]
        types = [
            "IN_USE" if self.claims.get(n, self) is not self and t != "NOT_FOUND" else t
            for n, t in zip(names, types, strict=True)
        ]
        if "NOT_FOUND" in types or "IN_USE" in types or not names:
            self.conn.send(rp.frame(rp.SETUP_INPUTS, b"\x00" + ",".join(types).encode()))
            return
        recipe = rp.Recipe(self._next_input_id, names, types)
        self._next_input_id += 1
        self.inputs[recipe.id] = recipe
        for n in names:
            self.claims[n] = self
        self.conn.send(rp.frame(rp.SETUP_INPUTS, bytes([recipe.id]) + ",".join(types).encode()))

    def publish(self, tick: int) -> int:
        """Send the data packages due at ``tick`` (after a late tick, only the latest); how
        many were sent."""
        if not self.started:
            return 0
        sent = self.sent
        for recipe in self.outputs:
            due = self._due.get(recipe.id, tick)
            if tick >= due:
                self.conn.send(recipe.pack([self.ctl.value(n) for n in recipe.names]))
                self.sent += 1
                self._due[recipe.id] = max(due + recipe.period_ticks, tick + 1)
        return self.sent - sent

    def closed(self) -> None:
        for name in [n for n, s in self.claims.items() if s is self]:
            del self.claims[name]
