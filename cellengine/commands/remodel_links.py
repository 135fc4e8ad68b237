"""What a REMODEL sequence row acts on, and the objects.yaml that the import writes.

A harness of one cable (the published sample) is written as that cable, on its connector, as
before harnesses existed. A harness of several cables is written as a harness named after its
first connector (HARNESS.md 1.6: REMODEL's EC, PC and T rows name it so), its branches being
the end_connector labels that RC rows name.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cellengine.errors import InputError, Problem, known
from cellengine.info.remodel_csv import CableRow, Components, ConnectorRow, Operation
from cellengine.info.remodel_harness import HarnessXml, PinnedCable

COMPONENTS = "Components_definition.csv"
HARNESS = "WH_configuration.xml"


@dataclass(frozen=True)
class Link:
    name: str  # the cable or harness of objects.yaml
    why: str  # for the plan's comment
    branch: str | None = None  # an RC row's branch of that harness


class Labels:
    """The sequence's labels resolved against the components and the harnesses."""

    def __init__(
        self, components: Components, harnesses: Sequence[HarnessXml] | None, sequence: Path
    ) -> None:
        self.components = components
        self.harnesses = harnesses
        self.sequence = sequence
        self.bundles = {h.first: h for h in harnesses or () if len(h.cables) > 1 and h.first}
        self.branches = {
            b.label: h for h in self.bundles.values() for b in h.branches if b.label and not b.free
        }
        self.in_bundle = {c.cable: h for h in self.bundles.values() for c in h.cables}

    def check(self, wh: Path) -> list[Problem]:
        """Each harness's cables are components; a harness of several cables names its
        first connector, a component."""
        out: list[Problem] = []
        c = self.components
        for h in self.harnesses or ():
            for cable in h.cables:
                if cable.cable not in c.cables:
                    msg = f"cable '{cable.cable}' is not defined in {COMPONENTS}" + known(c.cables)
                    out.append(Problem(msg, str(wh), cable.line))
            if len(h.cables) > 1 and h.first is None:
                msg = (
                    f"a harness of {len(h.cables)} cables needs first_connector, the connector "
                    "they all leave"
                )
                out.append(Problem(msg, str(wh), h.line))
            elif len(h.cables) > 1 and h.first not in c.connectors:
                msg = f"first_connector '{h.first}' is not a connector of {COMPONENTS}" + known(
                    c.connectors
                )
                out.append(Problem(msg, str(wh), h.line))
            if len(h.cables) > 1:
                out += _pins(h, wh)
        return out

    def link(self, op: Operation) -> Link:
        label, c = op.label, self.components
        if label in self.bundles:
            return Link(label, f"{label} is the first connector of a harness ({HARNESS})")
        if label in self.branches:
            h = self.branches[label]
            if op.kind != "RC":
                raise self._error(
                    op,
                    f"{label} is a branch of harness {h.first} ({HARNESS}); "
                    f"{op.kind} names the harness's connector, {h.first}",
                )
            return Link(str(h.first), f"{label} is a branch of harness {h.first}", label)
        if label in self.in_bundle:
            h = self.in_bundle[label]
            raise self._error(
                op,
                f"{label} is a cable of harness {h.first} ({HARNESS}); name the harness's "
                f"connector {h.first}, or (RC) one of its branches"
                + known([b.label for b in h.branches if b.label and not b.free]),
            )
        if label in c.cables:
            return Link(label, f"{label} is a cable")
        if label not in c.connectors:
            names = [*c.labels(), *self.branches]
            raise self._error(
                op,
                f"unknown Label '{label}': not a connector or cable of {COMPONENTS}"
                + (f" nor a branch of {HARNESS}" if self.harnesses is not None else "")
                + known(names),
            )
        return self._single(op)

    def _single(self, op: Operation) -> Link:
        """A connector on a single cable: the harness of one cable that it starts or ends."""
        label, c = op.label, self.components
        if self.harnesses is not None:
            ends = [
                h.cables[0].cable
                for h in self.harnesses
                if len(h.cables) == 1 and label in (h.first, h.branches[0].label)
            ]
            if ends:
                cable = ends[0]
                if cable not in c.cables:
                    raise self._error(
                        op,
                        f"{HARNESS} puts connector {label} on cable '{cable}', which "
                        f"{COMPONENTS} does not define" + known(c.cables),
                    )
                return Link(cable, f"connector {label} is on cable {cable} ({HARNESS})")
            firsts = [h.first for h in self.harnesses if h.first]
            raise self._error(
                op,
                f"connector '{label}' starts no harness in {HARNESS}"
                + (f" (its harnesses start at {', '.join(firsts)})" if firsts else "")
                + ': add its <wiring_harness first_connector="'
                + label
                + '">',
            )
        if len(c.cables) == 1:
            only = next(iter(c.cables))
            return Link(
                only, f"connector {label} is taken to be on {only}, the only cable in {COMPONENTS}"
            )
        raise self._error(
            op,
            f"cannot tell which cable connector '{label}' is on: there is no {HARNESS}, and "
            f"{COMPONENTS} has {len(c.cables)} cables" + known(c.cables),
        )

    def _error(self, op: Operation, message: str) -> InputError:
        return InputError(Problem(message, str(self.sequence), op.row))

    # --- objects.yaml ---------------------------------------------------------------------

    def single_connectors(self, from_plan: Mapping[str, str]) -> dict[str, str]:
        """Each single cable's connector: the one its plan steps name; else its harness's
        first connector (or its end's, when that is a component); else, with one connector
        and one cable, that connector."""
        out = dict(from_plan)
        c = self.components
        for h in self.harnesses or ():
            if len(h.cables) != 1:
                continue
            for connector in (h.first, h.branches[0].label):
                if connector is not None and connector in c.connectors:
                    out.setdefault(h.cables[0].cable, connector)
        if len(c.connectors) == 1 and len(c.cables) == 1:
            out.setdefault(next(iter(c.cables)), next(iter(c.connectors)))
        return out

    def harness_entries(self) -> list[tuple[str, dict[str, Any]]]:
        """(comment, {name: harness}) for each harness of several cables."""
        out = []
        c = self.components
        for first, h in self.bundles.items():
            k = c.connectors[first]
            cables = {p.cable: _harness_cable(c.cables[p.cable], p) for p in h.cables}
            branches = {
                b.label: {"cables": [p.cable for p in b.cables]}
                for b in h.branches
                if b.label and not b.free
            }
            data: dict[str, Any] = {"connector": connector_data(k)}
            if k.color:
                data["color"] = k.color
            data["cables"] = cables
            if branches and len(branches) == len(h.branches):
                data["branches"] = branches
            where = f"{HARNESS} line {h.line}, id {h.id}" if h.id else f"{HARNESS} line {h.line}"
            out.append((f"{where}; connector {first}, {COMPONENTS} row {k.row}", {first: data}))
        return out


def connector_data(k: ConnectorRow) -> dict[str, Any]:
    return {"type": k.type, "length": k.length, "width": k.width, "height": k.height}


def _harness_cable(row: CableRow, pins: PinnedCable) -> dict[str, Any]:
    """The cable's objects.yaml entry: the components file's sizes, its pins (a column not
    given is 0; the end pin only when Row2 is given)."""
    data: dict[str, Any] = {"length": row.length, "diameter": row.diameter}
    if row.color:
        data["color"] = row.color
    data["pin"] = [pins.row1 or 0, pins.col1 or 0]
    if pins.row2 is not None:
        data["end_pin"] = [pins.row2, pins.col2 or 0]
    return data


def _pins(h: HarnessXml, wh: Path) -> list[Problem]:
    """A harness of several cables orders them at the connector by Row1 (REMODEL's cable
    index, HARNESS.md 1.6): every cable needs one."""
    return [
        Problem(
            f"cable {p.cable} has no Row1: REMODEL orders a harness's cables at its first "
            "connector by Row1 (0 at the bottom)",
            str(wh),
            p.line,
        )
        for p in h.cables
        if p.row1 is None
    ]
