"""Every example YAML file names its JSON Schema for editors, and validates against it."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import pytest
import yaml

from tests.conftest import CELLS

EXAMPLES = sorted(CELLS.rglob("*.yaml"))
PREFIX = "# yaml-language-server: $schema="


def test_there_are_examples() -> None:
    assert len(EXAMPLES) >= 5


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: str(p.relative_to(CELLS)))
def test_example_names_its_schema_and_validates(path: Path) -> None:
    first = path.read_text().splitlines()[0]
    assert first.startswith(PREFIX), f"{path} must start with the $schema line"
    schema_path = (path.parent / first.removeprefix(PREFIX)).resolve()
    schema = json.loads(schema_path.read_text())
    jsonschema.validate(yaml.safe_load(path.read_text()), schema)


def test_schemas_catch_what_editors_should_flag() -> None:
    schemas = CELLS.parent / "schemas"
    plan = json.loads((schemas / "plan.schema.json").read_text())
    good = {"steps": [{"skill": "RouteCable", "cable": "c", "guides": ["p.e"]}]}
    jsonschema.validate(good, plan)
    for bad in (
        {"steps": [{"skill": "RouteCable", "cable": "c"}]},  # guides missing
        {"steps": [{"skill": "Fly", "cable": "c"}]},  # no such skill
        {"steps": [], "colour": "red"},  # unknown key
    ):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, plan)
