"""report.html's style sheet and scripts: files in cellengine/report/assets, shipped as package
data and found through importlib.resources, each one inlined in the page (nothing fetched)."""

from __future__ import annotations

import re
import textwrap
import tomllib
from fnmatch import fnmatch
from importlib.resources import files
from pathlib import Path

import pytest

from cellengine.report import page, write_report
from tests.conftest import ROOT
from tests.report.programs import cable_cell, sample_program


def resource_names() -> set[str]:
    return {p.name for p in (files("cellengine.report") / "assets").iterdir() if p.is_file()}


@pytest.fixture(scope="module")
def html(tmp_path_factory: pytest.TempPathFactory) -> str:
    world, cell = cable_cell()
    out = tmp_path_factory.mktemp("assets")
    _, html_path = write_report(out, sample_program(cell), world, cell, {"plan": "p.yaml"})
    return html_path.read_text(encoding="utf-8")


def test_assets_are_package_data() -> None:
    """importlib.resources finds every file of the folder, page.py uses each one, and each
    matches a package-data pattern of cellengine.report (so the wheel ships it)."""
    on_disk = {p.name for p in (ROOT / "cellengine/report/assets").iterdir() if p.is_file()}
    assert resource_names() == on_disk
    assert {page.STYLE, page.GUARD, *page.SCRIPTS} == on_disk
    assert len(page.SCRIPTS) == len(set(page.SCRIPTS))
    setuptools = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    patterns = setuptools["package-data"]["cellengine.report"]
    for name in on_disk:
        assert any(fnmatch(f"assets/{name}", p) for p in patterns), name


def test_every_asset_is_inlined(html: str) -> None:
    """The style sheet and the guard as they are, the script parts indented in one function,
    in order; their headers (for the source's reader and ESLint) left out."""
    assert f"<style>\n{page.asset(page.STYLE)}</style>" in html
    assert f"<script>\n{page.asset(page.GUARD)}</script>" in html
    at = [html.find(textwrap.indent(page.asset(name), "  ")) for name in page.SCRIPTS]
    assert -1 not in at and at == sorted(at), dict(zip(page.SCRIPTS, at, strict=True))
    for name in resource_names():
        header = (files("cellengine.report") / "assets" / name).read_text().partition("\n\n")[0]
        assert header not in html, name
    assert "/* global" not in html and "/* exported" not in html


def test_nothing_is_loaded_from_outside(html: str) -> None:
    tags = re.findall(r"<(?:script|link|img|iframe|object|embed)\b[^>]*>", html, re.I)
    assert tags and not [t for t in tags if re.search(r"\b(src|href|data)\s*=", t, re.I)]
    assert "<link" not in html.lower()


def test_an_asset_without_its_header_is_refused(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    (tmp_path / "x.js").write_text("const a = 1;\n", encoding="utf-8")
    monkeypatch.setattr(page, "ASSETS", tmp_path)
    with pytest.raises(ValueError, match=r"x\.js"):
        page.asset("x.js")


def test_no_asset_closes_its_element() -> None:
    """Inlined text cannot say '</script' or '</style' (the HTML parser would end the element)."""
    for name in resource_names():
        text = (files("cellengine.report") / "assets" / name).read_text().lower()
        assert "</script" not in text and "</style" not in text, name
