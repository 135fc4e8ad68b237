"""Time of `load_x3d` on a generated Blender-style 1 MB X3D and on the REMODEL combs.

Run: .venv/bin/python bench/bench_x3d.py [--runs N] [--size BYTES]
Goal: a 1 MB X3D loads in at most 0.2 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from cellengine.info.x3d import load_x3d

REMODEL = Path(__file__).resolve().parent.parent / "tests" / "data" / "shared" / "remodel"

HEAD = """<?xml version="1.0" encoding="UTF-8"?>
<!DOCTYPE X3D PUBLIC "ISO//Web3D//DTD X3D 3.0//EN" "http://www.web3d.org/specifications/x3d-3.0.dtd">
<X3D version="3.0" profile="Immersive">
\t<head>
\t\t<meta name="generator" content="bench_x3d.py, after Blender 2.83.0" />
\t</head>
\t<Scene>
\t\t<NavigationInfo headlight="true" type='"EXAMINE", "ANY"' avatarSize="0.25, 1.75, 0.75" />
\t\t<Transform DEF="ID0001"
\t\t           translation="0.000000 0.000000 0.000000"
\t\t           scale="0.001000 0.001000 0.001000"
\t\t           rotation="0.000000 0.707107 0.707107 3.141593"
\t\t           >
"""
TAIL = "\t\t</Transform>\n\t</Scene>\n</X3D>\n"


def element(i: int, rng: np.random.Generator, n_points: int) -> str:
    """One Blender-exported part: a Transform around an IndexedFaceSet of quads."""
    t = rng.uniform(0, 600, 3)
    pts = " ".join(f"{v:.6f}" for v in rng.uniform(-20, 20, 3 * n_points))
    quads = rng.integers(0, n_points, (n_points, 4))
    index = " ".join(f"{a} {b} {c} {d} -1" for a, b, c, d in quads)
    return f"""\t\t\t<Transform DEF="ID{i + 2:04d}"
\t\t\t           translation="{t[0]:.6f} {t[1]:.6f} {t[2]:.6f}"
\t\t\t           scale="1.000000 1.000000 1.000000"
\t\t\t           rotation="0.000000 1.000000 0.000000 {rng.uniform(0, 3):.6f}"
\t\t\t           >
\t\t\t\t<Shape>
\t\t\t\t\t<Appearance>
\t\t\t\t\t\t<Material diffuseColor="0.8 0.8 0.8" />
\t\t\t\t\t</Appearance>
\t\t\t\t\t<IndexedFaceSet solid="false"
\t\t\t\t\t                coordIndex="{index}"
\t\t\t\t\t                >
\t\t\t\t\t\t<Coordinate DEF="coords_ME_{i}"
\t\t\t\t\t\t            point="{pts}"
\t\t\t\t\t\t            />
\t\t\t\t\t</IndexedFaceSet>
\t\t\t\t</Shape>
\t\t\t</Transform>
"""


def blender_like(size: int, n_points: int = 40) -> tuple[str, int]:
    """A document of about ``size`` bytes and how many Transforms it holds."""
    rng = np.random.default_rng(0)
    parts = [HEAD]
    total, i = len(HEAD) + len(TAIL), 0
    while total < size:
        parts.append(element(i, rng, n_points))
        total += len(parts[-1])
        i += 1
    parts.append(TAIL)
    return "".join(parts), i


def median_time(f: Callable[[], object], runs: int) -> tuple[float, float]:
    f()  # warm the file cache and imports
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=15)
    ap.add_argument("--size", type=int, default=1 << 20)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "platform.x3d"
        text, n = blender_like(args.size)
        path.write_text(text)
        scene = load_x3d(path, Path(tmp))
        faces = sum(len(node.mesh.faces) for node in scene.nodes.values() if node.mesh)
        med, best = median_time(lambda: load_x3d(path, Path(tmp)), args.runs)
        print(
            f"generated Blender-style X3D, {path.stat().st_size / 1e6:.2f} MB, {n} Transforms, "
            f"{faces} triangles: median {med:.3f} s, min {best:.3f} s over {args.runs} runs"
        )
    combs = REMODEL / "combs_cad.x3d"
    if combs.is_file():
        med, best = median_time(lambda: load_x3d(combs, REMODEL), args.runs)
        print(
            f"{combs.name}, {combs.stat().st_size / 1e6:.2f} MB: median {med:.3f} s, "
            f"min {best:.3f} s over {args.runs} runs"
        )


if __name__ == "__main__":
    main()
