import json
from pathlib import Path

from cellengine.commands.schema import render, schemas
from tests.conftest import ROOT


def test_committed_schemas_are_up_to_date() -> None:
    """Run `cellengine schema` and commit the result when this fails."""
    for name, schema in schemas().items():
        committed = ROOT / "schemas" / name
        assert committed.read_text() == render(schema), f"{name} is out of date"


def test_plan_schema_has_one_branch_per_skill() -> None:
    plan = schemas()["plan.schema.json"]
    branches = plan["properties"]["steps"]["items"]["oneOf"]
    names = sorted(b["$ref"].rsplit("/", 1)[1] for b in branches)
    assert names == sorted(
        [
            "BimanualCarry",
            "ChangeTool",
            "Handover",
            "Pick",
            "PickCable",
            "Place",
            "PlaceConnector",
            "Pour",
            "RouteCable",
            "Tape",
            "Unscrew",
            "Weigh",
        ]
    )
    pick = plan["$defs"]["PickCable"]
    assert "from" in pick["properties"] and pick["additionalProperties"] is False


def test_schema_command_writes_files(tmp_path: Path) -> None:
    from cellengine.cli import main

    assert main(["schema", "--out", str(tmp_path)]) == 0
    written = json.loads((tmp_path / "cell.schema.json").read_text())
    assert written["$id"].endswith("cell.schema.json")
