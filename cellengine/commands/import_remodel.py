"""`cellengine import remodel SRC DEST`: turn a REMODEL cable-routing folder into a native
cell.yaml, objects.yaml and plan.yaml (DESIGN 3.2).

The REMODEL platform files are copied into DEST and used as they are (``format: remodel``);
the process CSVs become objects and plan steps. The platform files are read first, as
regular files inside SRC within the readers' size caps; then everything is written to a
staging folder next to DEST, validated there, and moved into place only when it validates,
so a failed import leaves DEST as it was.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import re
import shutil
import sys
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any, TypeVar

import yaml

from cellengine.commands.remodel_links import Labels, Link, connector_data
from cellengine.commands.remodel_tools import atc_tools
from cellengine.errors import (
    EXIT_OK,
    InputError,
    Problem,
    UsageError,
    display_path,
    known,
    printable,
)
from cellengine.info.cell import UrdfModel
from cellengine.info.files import read_capped, real
from cellengine.info.load import load_cell, load_plan, load_world
from cellengine.info.remodel import load_ids
from cellengine.info.remodel_csv import (
    Components,
    Operation,
    load_components,
    load_sequence,
)
from cellengine.info.remodel_harness import load_wiring
from cellengine.world import RefError, World

COMPONENTS = "Components_definition.csv"
SEQUENCE = "Assembly_sequence.csv"
HARNESS = "WH_configuration.xml"
MODELS = "Jigs_definition*.xml"  # the sample has Jigs_definition_v2.xml
# The reader's size cap of each kind of copied file (the .wri ids file is read as CSV).
_CAP_KINDS = {".x3d": "x3d", ".wri": "csv", ".xml": "xml"}
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_-]*$")
_SKILLS = {"EC": "PickCable", "PC": "PlaceConnector", "RC": "RouteCable", "T": "Tape"}
T = TypeVar("T")

# Without --robots: the two-arm cell of the published method (DESIGN 3.1), in mm and deg.
_HOME = [0, -90, 90, -90, -90, 0]
DEFAULT_SETUP: dict[str, Any] = {
    "units": {"length": "mm", "angle": "deg"},
    "robots": {
        arm: {
            "model": "ur5e",
            "base": {"xyz": [0, y, 0], "rpy": [0, 0, 0]},
            "tool": "cable_gripper",
            "home": _HOME,
        }
        for arm, y in (("left", 350), ("right", -350))
    },
    "tools": {
        "cable_gripper": {
            "kind": "parallel_gripper",
            "tcp": {"xyz": [0, 0, 200]},
            "finger_width": 20,
            "finger_thickness": 8,
            "jaw": {"open": 60, "slide": 7, "grasp": 4},
            # the reference cell's gripper (cells/cable_routing/cell.yaml): the jaw housing
            # on the flange, then the fingers
            "shape": [{"name": "body", "box": [50, 90, 110], "pose": {"xyz": [0, 0, 55]}}],
            "fingers": {"size": [8, 6, 90]},
        }
    },
    "driver": {"kind": "sim"},
    # the engine's default, written out: what a user tightens or loosens
    "clearance": 10,
}

DESCRIPTION = """\
Turn a REMODEL cable-routing folder into a native cell in DEST:

  cell.yaml     robots, tools and driver of --robots (default: two UR5e 'left' and
                'right' at y = +-350 mm with a cable gripper, in mm and deg); one
                platform per <name>_cad.x3d + <name>_ids.wri pair in SRC, copied to
                DEST/<name>/ with the shared Jigs_definition*.xml, as `format: remodel`
  objects.yaml  the cables of Components_definition.csv, each with its connector
                (the CSV's x, y, z are the connector's width, height and length);
                a WH_configuration.xml harness of several cables becomes a harness
                named after its first connector, its end_connector labels its branches
  plan.yaml     Assembly_sequence.csv, in file order as REMODEL runs it (its Order
                column is not used): EC -> PickCable, PC -> PlaceConnector (the
                spot's L/R picks robot left/right; with --arms auto, the engine),
                RC -> RouteCable (of a branch: its cables as a group), T -> Tape
                (between the first two spots' guides, held beside the third). A spot
                such as C2.1 is guide 1 of element C2 of whichever platform has
                C2. Labels are typed by their first letter as in REMODEL (T table,
                J jig, B box, C comb, A tool changer slot): J, B, C and A labels
                are unique across the platforms, tables may repeat.

The Label column names a connector (a harness's first connector names the harness),
a cable, or, in RC rows, a branch. What REMODEL itself would read otherwise (an Order
out of file order, a lower-case type, an EC arm its PC contradicts) is a warning at
its line. The later system's one-comb EC rows are read and checked, then refused at
their rows: the engine cannot do them yet.

A tool changer platform's A-labelled stations become tools with slots at their
tool_base (`Agun`: a taping gun `gun`; `Agripper_left`: the setup's gripper as
`gripper_left`, carried by robot `left` at the start), their TCP at the station's
tool_end, approached as REMODEL does.

Platforms are placed with --pose (default: at the cell origin). REMODEL's Blender
exports come out turned 180 deg about z in the z-up cell frame; a yaw of 180 lays
a platform's own axes along the cell's (as cells/cable_routing/cell.yaml does).

DEST is written only if the result validates; existing files there are kept unless
--force. Each YAML file starts with a yaml-language-server $schema line naming this
checkout's schemas/, relative to DEST (left out when cellengine is installed without
its schemas). A spot that no arm reaches (an IK check of each, fast) is a warning at
its row: the plan cannot run, most often for want of --pose. The plan is not compiled
here: `cellengine validate DEST` does that."""


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="turn another tool's files into a native cell",
        description="Turn another tool's files into a native cell, objects and plan.",
    )
    formats = p.add_subparsers(dest="format", metavar="FORMAT", required=True)
    r = formats.add_parser(
        "remodel",
        help="a REMODEL cable-routing folder",
        description=DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    r.add_argument("src", type=Path, metavar="SRC", help="the REMODEL folder")
    r.add_argument("dest", type=Path, metavar="DEST", help="the cell folder to write")
    r.add_argument(
        "--robots",
        type=Path,
        metavar="CELL.yaml",
        help="take robots, tools, driver, units and clearance from this cell (or its folder)",
    )
    r.add_argument(
        "--pose",
        action="append",
        default=[],
        type=pose_arg,
        metavar='[NAME=]"X Y Z ROLL PITCH YAW"',
        help="where the platforms are in the cell, in the units of the written "
        "cell.yaml (those of --robots; by default mm and deg), rpy as in URDF. "
        "With NAME= for one platform, else for all; repeatable; default zero. "
        'Write --pose="-100 0 0 0 0 0" when the first number is negative.',
    )
    r.add_argument(
        "--arms",
        choices=("file", "auto"),
        default="file",
        help="which arm places each connector: the one its PC spot's L or R names, as in "
        "REMODEL (file, the default), or the engine's choice (auto: arm: auto, for "
        "platforms placed where the sides the files were written for no longer fit)",
    )
    r.add_argument("--name", type=name_arg, help="the cell's name (default: DEST's folder name)")
    r.add_argument("--force", action="store_true", help="overwrite files that exist in DEST")
    r.set_defaults(run=run)


# --- what SRC holds ----------------------------------------------------------------------


@dataclass(frozen=True)
class Source:
    folder: Path
    platforms: Mapping[str, tuple[Path, Path]]  # name -> (cad, ids), sorted by name
    models: Path
    components: Path
    sequence: Path
    harness: Path | None

    def copies(self) -> dict[str, Path]:
        """Where each platform file goes, relative to DEST. The models file is shared."""
        out = {self.models.name: self.models}
        for name, (cad, ids) in self.platforms.items():
            out[f"{name}/{cad.name}"] = cad
            out[f"{name}/{ids.name}"] = ids
        return out


def find_source(src: Path) -> Source:
    if not src.is_dir():
        raise UsageError.at("no such folder", src)
    platforms = _platform_files(src)
    models = sorted(src.glob(MODELS))
    if len(models) != 1:
        what = "none" if not models else ", ".join(m.name for m in models)
        raise InputError.at(f"expected one {MODELS} (the element models), found {what}", src)
    for name in (COMPONENTS, SEQUENCE):
        if not (src / name).is_file():
            raise InputError.at(f"no {name} in the REMODEL folder", src)
    harness = src / HARNESS
    return Source(
        src,
        platforms,
        models[0],
        src / COMPONENTS,
        src / SEQUENCE,
        harness if harness.is_file() else None,
    )


def _platform_files(src: Path) -> dict[str, tuple[Path, Path]]:
    out: dict[str, tuple[Path, Path]] = {}
    for cad in sorted(src.glob("*_cad.x3d")):
        name = cad.name.removesuffix("_cad.x3d")
        ids = src / f"{name}_ids.wri"
        if not os.path.lexists(ids):  # there but not a regular file: read_copies says what
            raise InputError.at(
                f"no {ids.name} next to it: a platform is a <name>_cad.x3d and <name>_ids.wri pair",
                cad,
            )
        if not _NAME.match(name):
            raise InputError.at(
                f"platform name '{name}' is not a valid name: use letters, "
                "digits, '_' and '-', starting with a letter or '_'",
                cad,
            )
        out[name] = (cad, ids)
    for ids in sorted(src.glob("*_ids.wri")):
        if ids.name.removesuffix("_ids.wri") not in out:
            raise InputError.at(
                f"no {ids.name.removesuffix('_ids.wri')}_cad.x3d next to it: "
                "a platform is a <name>_cad.x3d and <name>_ids.wri pair",
                ids,
            )
    if not out:
        raise InputError.at("no platforms: expected <name>_cad.x3d and <name>_ids.wri pairs", src)
    return out


# REMODEL gives an element its type by its label's first letter (HARNESS.md 1.2). Spots name
# jigs, boxes, combs and tool changer slots by label alone, so those labels are unique across
# the platforms; tables are never named by a spot, and may repeat (T1 on two platforms).
LETTERS = {"T": "table", "J": "jig", "B": "box", "C": "comb", "A": "tool changer slot"}
# REMODEL's launcher reads these files by name and takes from each only these types
# (HARNESS.md 1.2); a label of another type there is one REMODEL would not see.
READS = {"platform": "JB", "combs": "C", "ATC": "A"}


def element_platforms(source: Source, warnings: list[Problem] | None = None) -> dict[str, str]:
    """Element label -> the platform it is on, for the labels a spot may name."""
    out: dict[str, str] = {}
    where: dict[str, tuple[Path, int]] = {}
    for name, (_, ids) in source.platforms.items():
        for row in load_ids(ids):
            letter = row.label[:1].upper()
            if letter not in LETTERS and warnings is not None:
                types = ", ".join(f"{k} ({v})" for k, v in LETTERS.items())
                msg = (
                    f"label '{row.label}' starts with none of {types}: REMODEL gives it no "
                    "type, and no spot can name it"
                )
                warnings.append(Problem(msg, str(ids), row.row))
            if letter not in LETTERS or letter == "T":
                continue
            if name in READS and letter not in READS[name] and warnings is not None:
                msg = (
                    f"{LETTERS[letter]} '{row.label}' is on platform '{name}': REMODEL takes "
                    f"only {' and '.join(LETTERS[k] + 's' for k in READS[name])} from "
                    f"{ids.name}; the import takes it where it is"
                )
                warnings.append(Problem(msg, str(ids), row.row))
            if row.label in out:
                first, line = where[row.label]
                raise InputError.at(
                    f"label '{row.label}' is also on platform '{out[row.label]}' "
                    f"({first.name} line {line}); spots name {LETTERS[letter]}s by label alone",
                    ids,
                    row.row,
                )
            out[row.label] = name
            where[row.label] = (ids, row.row)
    return out


# --- robots, tools, driver ---------------------------------------------------------------


@dataclass(frozen=True)
class Setup:
    data: dict[str, Any]  # units, robots, tools, driver, clearance as written in their file
    origin: str  # for comments and messages

    @property
    def robots(self) -> list[str]:
        return list(self.data["robots"])


def robot_setup(path: Path | None) -> Setup:
    """The --robots cell, validated, keeping its units; or the default two-arm setup."""
    if path is None:
        return Setup(DEFAULT_SETUP, "the default setup (two UR5e with cable grippers)")
    if path.is_dir():
        path = path / "cell.yaml"
    if not path.is_file():
        raise UsageError.at("--robots: no such cell file", path)
    cell, doc = load_cell(path)
    for name, robot in cell.robots.items():
        if isinstance(robot.model, UrdfModel):
            # Its URDF lives in that cell's folder, where DEST's cell may not reach.
            raise doc.error(
                f"robots.{name}.model: a URDF robot cannot be imported yet; "
                "copy the URDF into DEST and edit cell.yaml by hand",
                ("robots", name, "model"),
            )
    raw = doc.data
    data = {
        "units": raw.get("units", {"length": "m", "angle": "rad"}),
        "robots": raw["robots"],
        "tools": raw.get("tools") or {},
        "driver": raw.get("driver", {"kind": "sim"}),
    }
    if "clearance" in raw:  # the cell's (its units); else the default
        data["clearance"] = raw["clearance"]
    return Setup(data, display_path(path))


PoseArg = tuple[str | None, list[float]]


def pose_arg(value: str) -> PoseArg:
    """One --pose value: ``[NAME=]x y z roll pitch yaw`` (spaces or commas)."""
    name, sep, text = value.partition("=")
    if not sep:
        name, text = "", value
    parts = [t for t in re.split(r"[\s,]+", text.strip()) if t]
    try:
        numbers = [float(t) for t in parts]
    except ValueError:
        numbers = []
    if len(numbers) != 6 or not all(math.isfinite(v) for v in numbers):
        raise argparse.ArgumentTypeError(
            f"expected [NAME=]\"x y z roll pitch yaw\" (6 numbers), got '{value}'"
        )
    return (name.strip() or None), numbers


def name_arg(value: str) -> str:
    if not _NAME.match(value):
        raise argparse.ArgumentTypeError(
            f"'{value}' is not a valid name: use letters, digits, '_' and '-', "
            "starting with a letter or '_'"
        )
    return value


def platform_poses(
    values: Sequence[PoseArg], platforms: Sequence[str], src: Path
) -> dict[str, dict[str, Any]]:
    """Each platform's pose: its own --pose NAME=..., else the last --pose without a name,
    else zero."""
    general = [0.0] * 6
    named: dict[str, list[float]] = {}
    for name, numbers in values:
        if name is None:
            general = numbers
        elif name in platforms:
            named[name] = numbers
        else:
            raise UsageError.at(f"--pose: unknown platform '{name}'" + known(platforms), src)
    out = {}
    for p in platforms:
        v = [_plain(x) for x in named.get(p, general)]
        out[p] = {"xyz": v[:3], "rpy": v[3:]}
    return out


def _plain(x: float) -> float | int:
    return int(x) if x.is_integer() else x


# --- objects and plan --------------------------------------------------------------------


@dataclass(frozen=True)
class Step:
    row: int
    comment: str
    data: dict[str, Any]
    refs: tuple[tuple[str, str], ...]  # (reference kind, name): checked against the world


@dataclass(frozen=True)
class Inputs:
    """Everything read from SRC and the command line that the written files depend on."""

    source: Source
    setup: Setup
    components: Components
    operations: tuple[Operation, ...]
    labels: Labels
    elements: Mapping[str, str]  # element label -> platform
    arms: str = "file"  # --arms: "auto" leaves each PC's arm to the engine
    warnings: tuple[Problem, ...] = ()  # what REMODEL would read differently, at file:line


def read_inputs(source: Source, setup: Setup, arms: str = "file") -> Inputs:
    """Read every process file; report the problems of all of them, not only the first's."""
    problems: list[Problem] = []

    def attempt(read: Callable[[], T]) -> T | None:
        try:
            return read()
        except InputError as e:
            problems.extend(e.problems)
            return None

    components = attempt(lambda: load_components(source.components))
    warnings: list[Problem] = []
    operations = attempt(lambda: load_sequence(source.sequence, warnings))
    wh = source.harness
    wiring = attempt(lambda: load_wiring(wh)) if wh is not None else None
    elements = attempt(lambda: element_platforms(source, warnings))
    slots = attempt(lambda: atc_tools(source, setup.data))
    warnings += slots[2] if slots is not None else []
    harnesses = None
    if wiring is not None:
        harnesses, more = wiring
        warnings += more
    labels = None
    if components is not None and (wh is None or wiring is not None):
        labels = Labels(components, harnesses, source.sequence)
        problems += labels.check(wh) if wh is not None else []
    if problems or components is None or operations is None or elements is None or not labels:
        raise InputError(problems)
    return Inputs(source, setup, components, operations, labels, elements, arms, tuple(warnings))


def build_steps(inputs: Inputs) -> tuple[list[Step], dict[str, str], list[Problem]]:
    """Plan steps, the connector that each single cable's steps name (for objects.yaml),
    and warnings at the sequence's rows."""
    steps: list[Step] = []
    connectors: dict[str, str] = {}
    problems: list[Problem] = []
    routed: set[str] = set()  # the cables earlier RC rows route (REMODEL's routed_cables)
    for op in inputs.operations:
        try:
            link = inputs.labels.link(op)
            step = _step(op, link, inputs)
            if op.kind == "RC" and link.branch is not None:
                step = _separation(op, link.branch, step, routed, inputs)
            steps.append(step)
        except InputError as e:
            problems.extend(e.problems)
            continue
        if op.label in inputs.components.connectors and link.name in inputs.components.cables:
            connectors.setdefault(link.name, op.label)
    if problems:
        raise InputError(problems)
    return steps, connectors, _side_warnings(inputs)


# What the later REMODEL system does that the engine's skills do not do yet (issue #15).
_NOT_YET = {
    "EC": "picking from one comb with one hand (the later system's EC) is not built yet",
}


def _step(op: Operation, link: Link, inputs: Inputs) -> Step:
    single_comb = op.kind == "EC" and len(op.spots) == 1
    if single_comb:
        what = f"{op.kind} {op.label} {op.spot}: {_NOT_YET[op.kind]}"
        raise InputError.at(f"{what} in this engine (issue #15)", inputs.source.sequence, op.row)
    refs = [_ref(op, i, inputs) for i in range(len(op.spots))]
    # a branch is routed as a group, taken at its harness's connector first (the engine
    # inserts the separation and the grasp that REMODEL inserts, HARNESS.md 1.8)
    data = Block(skill=_SKILLS[op.kind], cable=link.branch or link.name)
    if op.kind == "EC":
        data["from"] = refs  # the Spot writes the connector end first, as PickCable does
    elif op.kind == "T":  # the two guides to tape between, then the one to hold beside
        data["between"], data["hold"] = refs[:2], refs[2]
    elif op.kind == "PC":
        data["guide"] = refs[0]
        arm = op.spots[0].arm
        if arm is not None and inputs.arms == "auto":
            data["arm"] = "auto"  # the letter need not name one of --robots' arms then
        elif arm is not None:
            _check_arm(op, arm, inputs)
            data["arm"] = arm
    else:
        data["guides"] = refs
    kind = "keypoint" if op.kind == "EC" else "guide"
    comment = f"row {op.row}: {op.kind} {op.label} {op.spot}; {link.why}"
    if op.kind == "PC" and inputs.arms == "auto" and op.spots[0].arm is not None:
        comment += f"; the engine chooses the arm, not the spot's {op.spots[0].arm} (--arms auto)"
    return Step(op.row, comment, data, tuple((kind, r) for r in refs))


def _separation(op: Operation, branch: str, step: Step, routed: set[str], inputs: Inputs) -> Step:
    """REMODEL's case A1 (HARNESS.md 1.8): a branch below cables of its harness still to be
    routed has those laid aside first in the separation guide J<id>S (its guide 1), which
    the step names as ``separate_into``; a folder without that guide is refused at the row."""
    h = inputs.labels.branches[branch]
    group = {c.cable: c.row1 for b in h.branches if b.label == branch for c in b.cables}
    remaining = {c.cable: c.row1 for c in h.cables if c.cable not in routed}
    routed.update(group)
    rows = [r for r in remaining.values() if r is not None]
    mine = [r for r in group.values() if r is not None]
    if len(group) >= len(remaining) or not mine or max(mine) >= max(rows, default=-1):
        return step
    above = ", ".join(n for n in remaining if n not in group)
    what = f"RC {branch} {op.spot}: {branch}'s cables leave the connector below {above}, still "
    if h.id is None:
        raise InputError.at(
            what + "to be routed: REMODEL lays those aside in their harness's separation guide "
            f"J<id>S first, and the harness has no id ({HARNESS} line {h.line})",
            inputs.source.sequence,
            op.row,
        )
    label = f"J{h.id}S"
    platform = inputs.elements.get(label)
    if platform is None:
        raise InputError.at(
            what + f"to be routed: REMODEL lays those aside in the separation guide {label} "
            "first, which no platform has (add it to a platform's ids file)",
            inputs.source.sequence,
            op.row,
        )
    ref = f"{platform}.{label}.1"
    step.data["separate_into"] = ref
    return replace(step, refs=(*step.refs, ("guide", ref)))


def _side_warnings(inputs: Inputs) -> list[Problem]:
    """An EC's arm letter that its PC's disagrees with: REMODEL takes the arm from the PC
    after the EC and never reads the EC's (HARNESS.md 1.7)."""
    out = []
    ops = inputs.operations
    for ec, pc in itertools.pairwise(ops):
        if ec.kind != "EC" or len(ec.spots) != 1 or ec.spots[0].arm is None:
            continue
        if pc.kind == "PC" and pc.spots[0].arm not in (None, ec.spots[0].arm):
            msg = (
                f"EC's spot names the {ec.spots[0].arm} arm, the PC after it (row {pc.row}) "
                f"the {pc.spots[0].arm}: REMODEL picks with the PC's arm, and so does the import"
            )
            out.append(Problem(msg, str(inputs.source.sequence), ec.row))
    return out


def _ref(op: Operation, i: int, inputs: Inputs) -> str:
    spot = op.spots[i]
    platform = inputs.elements.get(spot.element)
    if platform is None:
        raise InputError.at(
            f"unknown label '{spot.element}' in Spot '{op.spot}'" + known(inputs.elements),
            inputs.source.sequence,
            op.row,
        )
    return f"{platform}.{spot.element}.{spot.couple}"


def _check_arm(op: Operation, arm: str, inputs: Inputs) -> None:
    robots = inputs.setup.robots
    if arm not in robots:
        raise InputError.at(
            f"Spot '{op.spot}' names robot '{arm}', which {inputs.setup.origin} "
            "does not have" + known(robots),
            inputs.source.sequence,
            op.row,
        )


# --- writing -----------------------------------------------------------------------------


def schema_line(kind: str, dest: Path) -> list[str]:
    """The yaml-language-server line naming this checkout's schema, relative to DEST (so a
    cell committed inside the checkout works on any clone, and one beside it keeps working
    when both move together); absolute only where no relative path leads (another drive);
    none if cellengine has no schemas."""
    schema = Path(str(resources.files("cellengine.schemas") / f"{kind}.schema.json")).resolve()
    if not schema.is_file():
        return []
    try:
        ref = Path(os.path.relpath(schema, dest.resolve())).as_posix()
    except ValueError:  # another drive (Windows)
        ref = schema.as_posix()
    return [f"# yaml-language-server: $schema={ref}"]


class Block(dict[str, Any]):
    """A mapping always written in block style (a plan step, a cable)."""


class _Dumper(yaml.SafeDumper):
    def ignore_aliases(self, data: Any) -> bool:
        return True  # write a repeated value (two robots' home) out, not as &id001


def _scalar(v: Any) -> bool:
    return not isinstance(v, dict | list | tuple)


def _leaf(v: Any) -> bool:
    return _scalar(v) or (isinstance(v, list | tuple) and all(map(_scalar, v)))


def _represent_dict(dumper: yaml.SafeDumper, data: dict[str, Any]) -> yaml.Node:
    # Short mappings of numbers and number lists on one line, as people write them:
    # base: {xyz: [0, 350, 0], rpy: [0, 0, 0]}
    flow = (
        not isinstance(data, Block)
        and all(map(_leaf, data.values()))
        and len(yaml.safe_dump(data, default_flow_style=True, width=1000)) <= 60
    )
    return dumper.represent_mapping("tag:yaml.org,2002:map", data, flow_style=flow)


def _represent_list(dumper: yaml.SafeDumper, data: list[Any]) -> yaml.Node:
    return dumper.represent_sequence(
        "tag:yaml.org,2002:seq", data, flow_style=all(map(_scalar, data))
    )


_Dumper.add_representer(dict, _represent_dict)
_Dumper.add_representer(Block, _represent_dict)
_Dumper.add_representer(list, _represent_list)


def _dump(data: Any) -> str:
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False, width=100, allow_unicode=True)


def _document(kind: str, dest: Path, comments: Sequence[str], body: str) -> str:
    head = [*schema_line(kind, dest), *(f"# {c}" for c in comments)]
    return "\n".join(head) + "\n" + body


def _commented(items: Sequence[tuple[str, Any]]) -> str:
    """Entries of a mapping or list, indented two spaces, each after its comment line."""
    out = []
    for comment, data in items:
        text = _dump(data)
        out.append(f"  # {comment}\n" + "".join(f"  {line}" for line in text.splitlines(True)))
    return "".join(out)


def cell_text(inputs: Inputs, name: str, poses: Mapping[str, Any], dest: Path) -> str:
    source, setup = inputs.source, inputs.setup
    platforms = {
        p: {
            "pose": poses[p],
            "format": "remodel",
            "cad": f"{p}/{cad.name}",
            "ids": f"{p}/{ids.name}",
            "models": source.models.name,
        }
        for p, (cad, ids) in source.platforms.items()
    }
    tools, robots, _ = atc_tools(source, setup.data)
    data: dict[str, Any] = {"name": name, "units": setup.data["units"], "robots": robots}
    if tools:
        data["tools"] = tools
    data["platforms"] = platforms
    data["driver"] = setup.data["driver"]
    if "clearance" in setup.data:
        data["clearance"] = setup.data["clearance"]
    comments = [
        f"Imported from the REMODEL folder {source.folder} by `cellengine import remodel`.",
        f"Robots, tools and driver: {setup.origin}.",
        "Platform poses are in the units above; the REMODEL files they name are used as is.",
    ]
    return _document("cell", dest, comments, _dump(data))


def objects_text(inputs: Inputs, connectors: Mapping[str, str], dest: Path) -> str:
    c, labels = inputs.components, inputs.labels
    entries = []
    for label, cable in c.cables.items():
        if label in labels.in_bundle:
            continue  # written with its harness
        data = Block(length=cable.length, diameter=cable.diameter)
        if cable.color:
            data["color"] = cable.color
        comment = f"{COMPONENTS} row {cable.row}"
        if label in connectors:
            k = c.connectors[connectors[label]]
            data["connector"] = connector_data(k)
            comment += f"; connector {k.label}, row {k.row}"
        entries.append((comment, {label: data}))
    comments = [
        f"Imported from {c.file.name}. A connector's size is the CSV's x, y, z:",
        "width = x (across its wide face), height = y (its thickness), "
        "length = z (along the cable).",
    ]
    body = "units: {length: mm, mass: g}\n" + ("cables:\n" + _commented(entries) if entries else "")
    harnesses = labels.harness_entries()
    if harnesses:
        body += "harnesses:\n" + _commented(harnesses)
    return _document("objects", dest, comments, body)


def plan_text(steps: Sequence[Step], source: Source, dest: Path) -> str:
    comments = [f"Imported from {source.sequence.name}; each step says the row it comes from."]
    body = "cell: cell.yaml\nobjects: objects.yaml\nsteps:\n"
    body += _commented([(s.comment, [s.data]) for s in steps])
    return _document("plan", dest, comments, body)


def cell_name(given: str | None, dest: Path) -> str:
    """--name, else DEST's folder name made into a valid name."""
    if given is not None:
        return given
    name = re.sub(r"[^A-Za-z0-9_-]", "_", dest.name) or "remodel"
    return name if _NAME.match(name) else f"_{name}"


# --- staging, validating, moving into place ----------------------------------------------


def check_free(dest: Path, paths: Sequence[str], force: bool) -> None:
    if dest.exists() and not dest.is_dir():
        raise UsageError.at("DEST exists and is not a folder", dest)
    taken = [p for p in paths if (dest / p).exists() or (dest / p).is_symlink()]
    if taken and not force:
        raise UsageError.at(f"would overwrite {', '.join(taken)}; give --force to overwrite", dest)


@contextmanager
def staging(dest: Path) -> Iterator[Path]:
    """A fresh folder next to DEST (same file system, so moving is a rename), removed
    afterwards whatever happens. Made with mkdir, not mkdtemp, so that renamed to DEST it
    has the user's usual permissions rather than mkdtemp's 0700."""
    if not dest.parent.is_dir():
        raise UsageError.at("no such folder (DEST's parent)", dest.parent)
    tmp = dest.parent / f".{dest.name}.import-{os.getpid()}-{os.urandom(4).hex()}"
    tmp.mkdir()
    try:
        yield tmp
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def read_copies(source: Source) -> dict[str, bytes]:
    """The platform files to copy, read before anything is written: regular files inside
    SRC (a link may lead to one inside it), each within its reader's size cap. Never a
    stream: a link to /dev/zero filled the disk before anything was validated."""
    problems: list[Problem] = []
    out: dict[str, bytes] = {}
    folder = real(source.folder)
    for rel, path in source.copies().items():
        try:
            if not real(path).is_relative_to(folder):
                raise InputError.at(
                    "is a link that leads outside the REMODEL folder; copy the file itself into it",
                    path,
                )
            out[rel] = read_capped(path, _CAP_KINDS.get(path.suffix.lower(), "xml"))
        except InputError as e:
            problems.extend(e.problems)
    if problems:
        raise InputError(problems)
    return out


def write_files(tmp: Path, texts: Mapping[str, str], copies: Mapping[str, bytes]) -> None:
    for rel, text in texts.items():
        (tmp / rel).write_text(text, encoding="utf-8")
    for rel, data in copies.items():
        (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp / rel).write_bytes(data)  # contents only: REMODEL files are often read-only


def check_staged(tmp: Path, dest: Path, inputs: Inputs, steps: Sequence[Step]) -> World:
    """Load what was written as `cellengine validate` would. Spot references are checked
    first, so that a missing guide is reported at its row of the sequence CSV."""
    copies = inputs.source.copies()

    def remap(p: Problem) -> Problem:
        # Problems in the staged copies point at the SRC files a user would edit; a plan
        # step's at the row of the sequence it comes from; the rest of the written YAML's
        # at where it would have been written.
        for rel, src in copies.items():  # a message may name another staged copy
            p = replace(p, message=p.message.replace(str(tmp / rel), str(src)))
        if p.file is None or not real(Path(p.file)).is_relative_to(real(tmp)):
            return p
        rel = real(Path(p.file)).relative_to(real(tmp)).as_posix()
        step = re.match(r"steps\[(\d+)\]", p.message)
        if rel == "plan.yaml" and step is not None and int(step[1]) < len(steps):
            row = steps[int(step[1])].row
            return Problem(p.message, str(inputs.source.sequence), row)
        return replace(p, file=str(copies.get(rel, dest / rel)))

    try:
        world = load_world(tmp / "cell.yaml")
        _check_refs(world, steps, inputs)
        load_plan(tmp / "plan.yaml", lambda _: world)
    except InputError as e:
        note = Problem("nothing was written: the imported cell does not validate", str(dest))
        raise InputError([*map(remap, e.problems), note]) from None
    return world


def reach_warnings(
    world: World, steps: Sequence[Step], inputs: Inputs, posed: bool
) -> list[Problem]:
    """The spots of the plan that no arm reaches (or not the arm a step names), at their rows of
    the sequence: a plan that cannot run, most often platforms not placed (--pose). An IK
    check per spot and arm (cellengine/reach.py): milliseconds, where compiling takes seconds."""
    from cellengine.motion.robot import build_cell_model  # the motion stack, when it is needed
    from cellengine.reach import keypoint_reach

    refs = {ref for step in steps for kind, ref in step.refs if kind in ("keypoint", "guide")}
    reach = keypoint_reach(world, build_cell_model(world), sorted(refs))
    fix = "check --pose" if posed else "place the platforms in the cell with --pose"
    out = []
    for step in steps:
        arm = step.data.get("arm")
        arm = None if arm == "auto" else arm
        for _, ref in step.refs:
            if ref not in reach:
                continue
            if not reach[ref]:
                why = f"no arm reaches {ref}"
            elif arm is not None and arm not in reach[ref]:
                why = f"arm {arm} does not reach {ref}"
            else:
                continue
            message = f"{why} (the tool coming down its z): the plan cannot run; {fix}"
            out.append(Problem(message, str(inputs.source.sequence), step.row))
    return out


def _check_refs(world: World, steps: Sequence[Step], inputs: Inputs) -> None:
    problems = []
    for step in steps:
        for kind, ref in step.refs:
            try:
                world.check(kind, ref)
            except RefError as e:
                problems.append(Problem(str(e), str(inputs.source.sequence), step.row))
    if problems:
        raise InputError(problems)


def move_into_place(tmp: Path, dest: Path) -> None:
    """A new DEST is one rename; into an existing one, file by file (after validation,
    so only an OS failure can stop it half-way)."""
    if not dest.exists():
        tmp.rename(dest)
        return
    for f in sorted(tmp.rglob("*")):
        if f.is_file():
            target = dest / f.relative_to(tmp)
            target.parent.mkdir(parents=True, exist_ok=True)
            os.replace(f, target)


# --- the command -------------------------------------------------------------------------


def run(args: argparse.Namespace) -> int:
    dest = Path(os.path.abspath(args.dest))
    source = find_source(args.src)
    setup = robot_setup(args.robots)
    poses = platform_poses(args.pose, list(source.platforms), args.src)
    name = cell_name(args.name, dest)
    copies = source.copies()
    texts_names = ("cell.yaml", "objects.yaml", "plan.yaml")
    check_free(dest, [*texts_names, *copies], args.force)

    contents = read_copies(source)  # before anything is written
    inputs = read_inputs(source, setup, args.arms)
    steps, connectors, side_warnings = build_steps(inputs)
    texts = dict(
        zip(
            texts_names,
            (
                cell_text(inputs, name, poses, dest),
                objects_text(inputs, inputs.labels.single_connectors(connectors), dest),
                plan_text(steps, source, dest),
            ),
            strict=True,
        )
    )
    with staging(dest) as tmp:
        write_files(tmp, texts, contents)
        world = check_staged(tmp, dest, inputs, steps)
        warnings = reach_warnings(world, steps, inputs, bool(args.pose))
        move_into_place(tmp, dest)
    print(
        printable(
            f"{display_path(dest)}: cell.yaml (platforms {', '.join(source.platforms)}), "
            f"objects.yaml ({_count(len(inputs.components.cables), 'cable')}), "
            f"plan.yaml ({_count(len(steps), 'step')})"
        )
    )
    for w in [*inputs.warnings, *side_warnings, *warnings]:
        print(w.warning(), file=sys.stderr)
    # honest about what was checked: files and reach, not the motion
    print(printable(f"not compiled: `cellengine validate {display_path(dest)}` compiles the plan"))
    return EXIT_OK


def _count(n: int, what: str) -> str:
    return f"{n} {what}{'' if n == 1 else 's'}"
