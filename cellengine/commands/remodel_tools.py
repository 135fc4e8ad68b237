"""The tool changer of a REMODEL folder's ATC platform as cell.yaml tools with slots (issue
#15).

REMODEL gives each tool an A-labelled element: the label without its 'A' names the tool
(``Agun``: gun, ``Agripper_left``: gripper_left; HARNESS.md 1.2), and the element's Jigs
ATC_station says which kind it holds (``tool="gun"`` or ``"gripper"``), where the tool's base
sits (``tool_base``, a keypoint of the element) and the tool's action frame on that base
(``tool_end``). Each becomes a tool whose slot is at its ``tool_base``:

- a gun: a taping gun, a box of its ``tool_dim`` on the flange, its TCP at ``tool_end``,
  taping for REMODEL's 3 s;
- a gripper: the setup's gripper (the one its robot carries), its TCP at ``tool_end``.

The approach is REMODEL's (ATC.changeTool, HARNESS.md 2.6): a seated tool slides out 70 mm
along the slot's x, then back 50 mm plus the tool's length along its z; the bare flange
leaves a seated tool 50 mm back along z. A robot whose name ends a gripper's name
(``gripper_left``: ``left``) starts carrying it. REMODEL converts its wrist to the tool base
with its Motoman changer's offsets (ATC_dist, ATC_angle), which are its robot's and in no
folder file: here the seated flange is at ``tool_base`` itself, which a warning says.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from cellengine import geometry as g
from cellengine.errors import Problem
from cellengine.info.remodel import load_ids, load_jigs
from cellengine.info.units import ANGLE, LENGTH

SLIDE = 0.070  # m: REMODEL's vert_offset, the slide out of the slot along its x
BACK = 0.050  # m: REMODEL's z_offset, back along the slot's z
TAPING_S = 3.0  # s: REMODEL's gun node sleeps this long ("Taping time", HARNESS.md 2.6)
KINDS = {"gun": "taping_gun", "gripper": "parallel_gripper"}


def atc_tools(
    source: Any, setup: Mapping[str, Any]
) -> tuple[dict[str, Any], dict[str, Any], list[Problem]]:
    """The tools of ``source``'s tool changer stations (in ``setup``'s units), the setup's
    robots with each starting on its own gripper, and warnings at the ids files' lines."""
    tools: dict[str, Any] = dict(setup["tools"])
    robots: dict[str, Any] = copy.deepcopy(dict(setup["robots"]))
    warnings: list[Problem] = []
    jigs = load_jigs(source.models)
    length = LENGTH[setup["units"].get("length", "m")]
    angle = ANGLE[setup["units"].get("angle", "rad")]
    for platform, (_, ids) in source.platforms.items():
        for row in load_ids(ids):
            model = jigs.get(row.model)
            if not row.label.startswith("A") or model is None or model.tool not in KINDS:
                continue
            name = row.label[1:]
            base = robots_gripper(tools, robots)
            spec = _tool(model, base, length, angle)
            spec["slot"] = _slot(f"{platform}.{row.label}.tool_base", model, length)
            tools[name] = spec
            carrier = next((r for r in robots if name.endswith(f"_{r}")), None)
            if carrier is not None and spec["kind"] == "parallel_gripper":
                robots[carrier]["tool"] = name
            warnings.append(
                Problem(
                    f"tool '{name}' is seated with the flange at its station's tool_base: "
                    "REMODEL's own offsets from its robot's wrist (ATC_dist, ATC_angle) are "
                    "in no folder file; check the slot against the real changer",
                    str(ids),
                    row.row,
                )
            )
    return tools, robots, warnings


def robots_gripper(tools: Mapping[str, Any], robots: Mapping[str, Any]) -> Mapping[str, Any]:
    """The setup's gripper: the first robot's tool that is a parallel gripper."""
    for robot in robots.values():
        tool: Mapping[str, Any] | None = tools.get(robot.get("tool") or "")
        if tool is not None and tool.get("kind") == "parallel_gripper":
            return tool
    return {}


def _tool(model: Any, gripper: Mapping[str, Any], length: float, angle: float) -> dict[str, Any]:
    end = model.keypoints.get("tool_end")
    tcp = _pose(end.T_element_keypoint if end is not None else np.eye(4), length, angle)
    if model.tool == "gripper":
        spec = copy.deepcopy(dict(gripper)) or {"kind": "parallel_gripper"}
        spec["tcp"] = tcp
        return spec
    dims = model.dimensions
    box = [dims.get(f"tool_{k}", 0.0) / length for k in "xyz"]
    spec = {"kind": "taping_gun", "tcp": tcp, "dwell": TAPING_S}
    if min(box) > 0:
        spec["shape"] = [{"name": "body", "box": _round(box), "pose": {"xyz": [0, 0, box[2] / 2]}}]
    return spec


def _slot(at: str, model: Any, length: float) -> dict[str, Any]:
    z_tool = model.dimensions.get("tool_z", 0.0)
    slide, back = SLIDE / length, BACK / length
    return {
        "at": at,
        "exit": [[_r(slide), 0, 0], [_r(slide), 0, _r(-back - z_tool / length)]],
        "retreat": [[0, 0, _r(-back)]],
    }


def _pose(T: Any, length: float, angle: float) -> dict[str, Any]:
    xyz, rpy = g.xyz_rpy(np.asarray(T, dtype=float))
    return {"xyz": _round(xyz / length), "rpy": _round(rpy / angle)}


def _r(x: float) -> float | int:
    v = round(float(x), 6)
    return int(v) if v == int(v) and math.isfinite(v) else v


def _round(values: Any) -> list[float | int]:
    return [_r(v) for v in values]
