import tomllib

from tests.conftest import ROOT


def test_every_package_is_listed_in_pyproject() -> None:
    """pyproject lists packages by hand (schemas/ ships as cellengine.schemas, skills/ as
    cellengine.skills): a new subpackage left out of the list would be missing from a wheel."""
    listed = set(
        tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    )
    found = {
        ".".join(p.parent.relative_to(ROOT).parts) for p in ROOT.glob("cellengine/**/__init__.py")
    }
    found |= {
        f"cellengine.{p.parent.relative_to(ROOT).as_posix()}".replace("/", ".")
        for p in (ROOT / "skills").rglob("__init__.py")
    }
    assert found | {"cellengine.schemas"} == listed
