"""The copy of objects.yaml that `locate --out` writes: the file's own text with each located
container's `at` replaced or added."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from cellengine.info.load import load_objects
from cellengine.info.objects import Objects
from cellengine.info.units import Units
from cellengine.info.yamlio import load_yaml
from cellengine.locate.objects import Found
from cellengine.locate.rewrite import at_text, rewritten

TEXT = """\
# the bench's objects
units: {length: mm, mass: g}
containers:
  a: {kind: vial, diameter: 28, height: 60, marker: 4, at: bench.rack1.slot1}  # kept
  b:
    kind: vial        # block style
    diameter: 28
    height: 60
    at: "bench.rack1.slot2"
  c: {kind: vial, diameter: 28, height: 60, at: {xyz: [1, 2, 3]}}
  d: {kind: vial, diameter: 28, height: 60}
  e:
    kind: box
    size: [10, 10, 10]
"""


def test_each_at_is_replaced_or_added_and_the_rest_kept(tmp_path: Path) -> None:
    path = tmp_path / "objects.yaml"
    path.write_text(TEXT)
    values = {
        "a": "{xyz: [550.1, 230, 0]}",
        "b": "bench.free1",
        "c": "bench.free2",
        "d": "bench.free3",
        "e": "{xyz: [1, 2, 0], rpy: [0, 0, 0.5]}",
    }
    new = rewritten(TEXT, load_yaml(path), values)
    assert new.splitlines() == [
        "# the bench's objects",
        "units: {length: mm, mass: g}",
        "containers:",
        "  a: {kind: vial, diameter: 28, height: 60, marker: 4, at: {xyz: [550.1, 230, 0]}}"
        "  # kept",
        "  b:",
        "    kind: vial        # block style",
        "    diameter: 28",
        "    height: 60",
        "    at: bench.free1",
        "  c: {kind: vial, diameter: 28, height: 60, at: bench.free2}",
        "  d: {at: bench.free3, kind: vial, diameter: 28, height: 60}",
        "  e:",
        "    at: {xyz: [1, 2, 0], rpy: [0, 0, 0.5]}",
        "    kind: box",
        "    size: [10, 10, 10]",
    ]
    path.write_text(new)
    objects = load_objects(path)
    assert objects.containers["a"].at is not None
    assert objects.containers["e"].at is not None


def test_an_at_written_over_several_lines_is_refused(tmp_path: Path) -> None:
    text = (
        "containers:\n  a:\n    kind: vial\n    diameter: 28\n    height: 60\n"
        "    at:\n      xyz: [1, 2, 3]\n"
    )
    path = tmp_path / "objects.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=r"line 7: containers\.a\.at is a block mapping"):
        rewritten(text, load_yaml(path), {"a": "bench.free1"})


def test_a_place_is_written_to_a_hundredth_of_a_millimetre_in_the_files_unit() -> None:
    found = Found("a", 4, np.array([0.5500612, 0.23, 0.0]), 0.3, None, math.inf)
    assert at_text(found, Objects(units=Units(length="m")), box=False) == (
        "{xyz: [0.55006, 0.23, 0]}"
    )
    assert at_text(found, Objects(units=Units(length="mm")), box=False) == (
        "{xyz: [550.06, 230, 0]}"
    )
    assert at_text(found, Objects(units=Units(length="mm", angle="deg")), box=True) == (
        "{xyz: [550.06, 230, 0], rpy: [0, 0, 17.1887]}"
    )
