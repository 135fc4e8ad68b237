"""Native platforms (DESIGN 3.2): an X3D assembly, an element-model XML and a mapping CSV.

Each map row names a DEF in the X3D, the model it is an instance of, and the element's name
in plans. The element's frame is the DEF'd node's rigid frame; its dimensions and keypoints
come from the model.

Every CAD part with geometry is in the collision scene: a part no row names (a plate, a
bracket added to the X3D and forgotten in the map) is an obstacle named by its DEF, with a
warning. Two models are words of the map, not of models.xml: ``obstacle`` (the part is an
obstacle under the row's name, no warning) and ``ignore`` (the part is not an obstacle: a
label, a part the cable passes through).
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import Literal

import numpy as np

from cellengine.arrays import Mat
from cellengine.errors import InputError, Problem, known
from cellengine.info.mapcsv import IGNORE, OBSTACLE, MapRow, load_map
from cellengine.info.models_xml import ElementModel, load_models
from cellengine.info.platform import Element, Platform, Source, frozen_array
from cellengine.info.x3d import X3DNode, X3DScene, load_x3d


def load_native_platform(
    name: str,
    T_cell_platform: Mat,
    cad: Path,
    models: Path,
    map: Path,
    root: Path,
    up: Literal["y", "z"] = "y",
) -> Platform:
    """Read a native platform; paths are already resolved inside the cell folder ``root``."""
    element_models = load_models(models)
    rows = load_map(map)
    scene = load_x3d(cad, root, up)
    return assemble(name, T_cell_platform, scene, element_models, rows, models, map)


def assemble(
    name: str,
    T_cell_platform: Mat,
    scene: X3DScene,
    models: Mapping[str, ElementModel],
    rows: Sequence[MapRow],
    models_file: Path,
    map_file: Path,
) -> Platform:
    elements: dict[str, Element] = {}
    for row in rows:
        node = scene.node(row.cad_name, map_file, row.row)
        if row.model == IGNORE:
            continue
        if row.model == OBSTACLE:
            note = f"an obstacle ({map_file.name} row {row.row}), not an element with keypoints"
            elements[row.name] = _obstacle(row.name, node, Source(str(map_file), row.row), note)
            continue
        model = models.get(row.model)
        if model is None:
            raise InputError.at(
                f"unknown model '{row.model}' (not in {models_file.name}){known(models)}",
                map_file,
                row.row,
            )
        elements[row.name] = Element(
            name=row.name,
            model=row.model,
            T_platform_element=node.T_scene_node,
            dimensions=model.dimensions,
            keypoints=model.keypoints,
            mesh=node.mesh,
            source=Source(str(map_file), row.row),
        )
    warnings = _unmapped(name, scene, {row.cad_name for row in rows}, elements, map_file)
    return Platform(
        name, frozen_array(T_cell_platform), MappingProxyType(elements), tuple(warnings)
    )


def _unmapped(
    platform: str,
    scene: X3DScene,
    mapped: set[str],
    elements: dict[str, Element],
    map_file: Path,
) -> list[Problem]:
    """Each CAD part with geometry that no row names, added to ``elements`` as an obstacle
    named by its DEF (the geometry under no DEF as 'unnamed'); a warning for each."""
    parts: list[tuple[str, X3DNode, str, int | None]] = [
        (n.name, n, n.file, n.line) for n in scene.nodes.values() if n.name not in mapped
    ]
    loose = X3DNode("unnamed", scene.file, 0, np.eye(4), scene.mesh)
    parts.append(("unnamed", loose, scene.file, None))
    warnings = []
    for cad, node, file, line in parts:
        if node.mesh is None or len(node.mesh.faces) == 0:
            continue
        name = _free_name(re.sub(r"[.\s]", "_", cad), elements)
        note = f"a CAD part no row of {map_file.name} names: an obstacle"
        elements[name] = _obstacle(name, node, Source(file, line or 1), note)
        what = "geometry under no DEF" if node is loose else f"CAD part '{cad}'"
        warnings.append(
            Problem(
                f"{what} is in no row of {map_file.name}: it is checked as the obstacle "
                f"'{platform}.{name}'; give it a row (its model, or 'obstacle' or 'ignore')",
                file,
                line,
            )
        )
    return warnings


def _obstacle(name: str, node: X3DNode, source: Source, note: str) -> Element:
    """A part of the scene that plans do not name a keypoint of: collision geometry only."""
    return Element(
        name=name,
        model=OBSTACLE,
        T_platform_element=node.T_scene_node,
        dimensions=MappingProxyType({}),
        keypoints=MappingProxyType({}),
        mesh=node.mesh,
        source=source,
        note=note,
    )


def _free_name(name: str, taken: Mapping[str, Element]) -> str:
    """``name``, or with a suffix when a mapped element has it already."""
    out, k = name, 1
    while out in taken:
        k += 1
        out = f"{name}_{k}"
    return out
