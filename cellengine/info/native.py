"""Native platforms (DESIGN 3.2): an X3D assembly, an element-model XML and a mapping CSV.

Each map row names a DEF in the X3D, the model it is an instance of, and the element's name
in plans. The element's frame is the DEF'd node's rigid frame; its dimensions and keypoints
come from the model. X3D nodes that no row names are not elements.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from types import MappingProxyType
from typing import Literal

from cellengine.arrays import Mat
from cellengine.errors import InputError, known
from cellengine.info.mapcsv import MapRow, load_map
from cellengine.info.models_xml import ElementModel, load_models
from cellengine.info.platform import Element, Platform, Source, frozen_array
from cellengine.info.x3d import X3DScene, load_x3d


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
    return Platform(name, frozen_array(T_cell_platform), MappingProxyType(elements))
