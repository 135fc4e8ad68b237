"""Plain JSON values from whatever a report carries: numpy arrays and scalars, tuples,
mappings, dataclasses (a GateReport), paths. Non-finite floats become None (JSON has no NaN)."""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping, Set
from pathlib import PurePath
from typing import Any

import numpy as np

Json = None | bool | int | float | str | list["Json"] | dict[str, "Json"]


def jsonable(value: Any) -> Json:
    """``value`` as JSON data (recursively); anything unknown as its ``str``."""
    if value is None or isinstance(value, bool | str):
        return value
    if isinstance(value, int | np.integer):
        return int(value)
    if isinstance(value, float | np.floating):
        f = float(value)
        return f if math.isfinite(f) else None
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, Set):
        return [jsonable(v) for v in sorted(value, key=str)]
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return _dataclass(value)
    if isinstance(value, enum.Enum):
        return jsonable(value.value)
    if isinstance(value, PurePath):
        return str(value)
    return str(value)


def _dataclass(value: Any) -> dict[str, Json]:
    out = {
        f.name: jsonable(getattr(value, f.name))
        for f in dataclasses.fields(value)
        if not f.name.startswith("_")
    }
    ok = getattr(value, "ok", None)  # a GateReport's verdict is a property
    if isinstance(ok, bool) and "ok" not in out:
        out["ok"] = ok
    violations = getattr(value, "violations", None)
    if isinstance(violations, tuple | list):  # Violation.__str__ says it in words
        out["violations"] = [str(v) for v in violations]
    return out
