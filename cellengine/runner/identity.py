"""A run's identity, journaled at its ``start``: what its program was compiled from (the plan,
cell and objects files by content, the execution mode, the engine's version). ``--resume``
goes on only with the same, so it never plays the rest of one program after another's
first segments (split, sync and async compile to the same segment labels)."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cellengine import __version__

if TYPE_CHECKING:
    from cellengine.pipeline import Compiled

FILES = ("plan", "cell", "objects")


def run_identity(compiled: Compiled) -> dict[str, str]:
    """Each input file's SHA-256 (by role), the execution mode and the engine's version."""
    plan = compiled.loaded.plan
    paths = {"plan": plan.file, "cell": compiled.world.cell_file}
    if plan.objects is not None:
        paths["objects"] = plan.file.parent / plan.objects
    out = {role: _digest(path) for role, path in paths.items()}
    out = {**out, "execution": compiled.strategy, "version": __version__}
    if compiled.located:
        out["located"] = json.dumps(compiled.located, sort_keys=True)
    factor = compiled.context.speed.factor
    return out if factor == 1.0 else {**out, "speed": f"{factor:g}"}


def differences(journaled: dict[str, Any], now: dict[str, str]) -> list[str]:
    """What differs between the identity a run started with and the files now, in words."""
    out = [f"the {role} file changed" for role in FILES if journaled.get(role) != now.get(role)]
    if journaled.get("execution") != now["execution"]:
        out.append(f"the execution was {journaled.get('execution')}, now {now['execution']}")
    if journaled.get("speed", "1") != now.get("speed", "1"):
        out.append(f"--speed was {journaled.get('speed', '1')}, now {now.get('speed', '1')}")
    if journaled.get("located") != now.get("located"):
        out.append("the containers' places located by the camera (--locate) differ")
    if journaled.get("version") != now["version"]:
        out.append(f"cellengine was {journaled.get('version')}, now {now['version']}")
    return out


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()
