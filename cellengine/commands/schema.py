"""`cellengine schema`: write JSON Schemas of cell, objects and plan files.

Editors use them through the yaml-language-server `$schema` line at the top of each file.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from cellengine.errors import EXIT_OK
from cellengine.family import families
from cellengine.info.cell import Cell
from cellengine.info.objects import Objects
from cellengine.info.plan import PlanFile

BASE = "https://cellengine.dev/schemas/"


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="write JSON Schemas of the YAML files",
        description="Write cell, objects and plan JSON Schemas into a folder.",
    )
    p.add_argument("--out", type=Path, default=Path("schemas"), help="folder (default: schemas)")
    p.set_defaults(run=run)


def schemas() -> dict[str, dict[str, Any]]:
    """File name -> schema. Plan steps are one schema per registered skill, by `skill`."""
    plan = PlanFile.model_json_schema()
    defs = plan.setdefault("$defs", {})
    refs = []
    for name, cls in sorted(families().skills.items()):
        s = cls.model_json_schema(ref_template="#/$defs/{model}")
        defs.update(s.pop("$defs", {}))
        defs[name] = s
        refs.append({"$ref": f"#/$defs/{name}"})
    plan["properties"]["steps"]["items"] = {"oneOf": refs}
    out = {"cell": Cell.model_json_schema(), "objects": Objects.model_json_schema(), "plan": plan}
    result = {}
    for kind, schema in out.items():
        schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
        schema["$id"] = f"{BASE}{kind}.schema.json"
        result[f"{kind}.schema.json"] = schema
    return result


def render(schema: dict[str, Any]) -> str:
    return json.dumps(schema, indent=2, sort_keys=True) + "\n"


def run(args: argparse.Namespace) -> int:
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    for name, schema in schemas().items():
        (out / name).write_text(render(schema))
        print(out / name)
    return EXIT_OK
