"""report.html: one self-contained page (inline CSS and JS, the data as embedded JSON, system
fonts; nothing is fetched). :func:`render_page` fills the template.

The style sheet and the scripts are files in ``cellengine/report/assets`` (package data, read
with importlib.resources at each render and inlined). The page's script is a small canvas
renderer (perspective camera orbiting a target, painter's algorithm over shaded triangles,
capsules drawn as thick round-capped strokes), the time slider and playback, joint plots, the
step timeline and the steps table; no library. Its parts (:data:`SCRIPTS`) are joined, in order,
into one function.

No three.js or uPlot (decided when the assets became files): the replay carries the cell's
meshes as triangles and the arms as their collision shapes (capsules, spheres, boxes), which the
canvas draws. three.js (0.187 on npm: core and module 2.1 MB, about 0.7 MB minified, all inlined
since the page fetches nothing) would nearly triple a typical page (0.39 MB) to draw the same
shapes, and is one more vendored library to keep current. Real robot meshes would first need
their triangles in the replay data; with many of them a depth buffer (WebGL) would beat the
painter's algorithm and be worth its size. The plots are a few canvas lines with a cursor, step
bands and limits; uPlot (51 KB) would replace them, not improve them.

The data (``#ce-data``): ``{"report": report_data(...), "replay": replay_data(...), "title"}``.
When the page has drawn, ``body[data-status]`` is ``ok``, ``body[data-canvas]`` the 3D
canvas's rectangle (x,y,w,h in CSS pixels), ``data-drawn`` the number of shapes and
``data-cables`` of cable lines in the first frame; on any error the status is ``error`` and
``#errors`` says why (tests read these with a headless browser's --dump-dom). The page's URL
may say where to start: ``#t=2.5&az=-0.75&el=0.55`` (seconds from the start, camera angles).
"""

from __future__ import annotations

import html
import json
import textwrap
from collections.abc import Mapping, Sequence
from importlib.resources import files
from typing import Any

import numpy as np
from numpy.typing import NDArray

ASSETS = files("cellengine.report") / "assets"
STYLE = "page.css"
GUARD = "guard.js"  # runs first: catches the errors of the page's script into the DOM
SCRIPTS = (
    "base.js",
    "time.js",
    "units.js",
    "scene.js",
    "objects.js",
    "labels.js",
    "closest.js",
    "draw.js",
    "plots.js",
    "panels.js",
    "reach.js",  # the cell page's (cell_page.py); nothing without the replay's ``reach``
    "run.js",
    "camera.js",
    "failure.js",
    "main.js",
)


def asset(name: str) -> str:
    """An asset's text as inlined: without its header, the comments up to the first blank line
    (what a part is, ESLint's /* global */ lists), which are for the source's reader."""
    text = (ASSETS / name).read_text(encoding="utf-8")
    header, blank, body = text.partition("\n\n")
    if not blank or not header.startswith(("//", "/*")):
        raise ValueError(f"report asset {name}: no header comment followed by a blank line")
    return body


def script() -> str:
    """The page's script: the parts in one function (their shared scope), strict."""
    parts = "\n".join(asset(name) for name in SCRIPTS)
    return "'use strict';\n(function () {\n" + textwrap.indent(parts, "  ") + "})();\n"


BODY = r"""
<header>
  <h1 id="title"></h1><span class="sub" id="subtitle"></span>
  <div class="chips" id="chips"></div>
</header>
<div class="wrap">
  <section class="panel fail" id="failure-panel" hidden></section>
  <div class="row1">
    <section class="panel">
      <div id="view-wrap">
        <canvas id="view" aria-label="3D replay of the cell"></canvas>
        <div class="hud" id="hud-step"></div>
        <div class="hud" id="hud-legend"></div>
        <div class="hud" id="hud-help">drag: orbit &middot; shift/right-drag: pan &middot;
          wheel: zoom &middot; double-click: reset</div>
      </div>
      <div class="controls">
        <button id="play" title="play / pause (space)">&#9654; Play</button>
        <input type="range" id="slider" min="0" max="1" step="0.001" value="0"
          aria-label="time">
        <span id="clock"></span>
        <select id="speed" title="playback speed">
          <option value="0.25">0.25&times;</option><option value="0.5">0.5&times;</option>
          <option value="1" selected>1&times;</option><option value="2">2&times;</option>
          <option value="4">4&times;</option>
        </select>
        <button id="btn-trails" class="on" title="fingertip paths">paths</button>
        <button id="btn-keys" title="keypoints">keypoints</button>
        <button id="btn-wire" title="static meshes as wireframe">wire</button>
        <button id="btn-reset" title="reset the view">view</button>
        <button id="btn-fail" title="the pose where the compile stopped" hidden>failure</button>
      </div>
    </section>
    <aside class="panel" id="now"></aside>
  </div>
  <section class="panel">
    <h2>Step timeline</h2>
    <div id="timeline"></div>
  </section>
  <section class="panel">
    <h2>Joints</h2>
    <div class="plots" id="plots"></div>
  </section>
  <section class="panel">
    <h2>Steps and segments</h2>
    <div style="overflow-x:auto"><table id="steps"></table></div>
  </section>
  <section class="panel" id="details-panel" hidden>
    <h2>Run</h2>
    <dl class="kv" id="details"></dl>
  </section>
</div>
"""


def template() -> str:
    """The page around ``__CE_TITLE__`` and ``__CE_DATA__``; the assets are read each time."""
    return (
        "<!DOCTYPE html>\n<html lang='en'>\n<head>\n<meta charset='utf-8'>\n"
        "<meta name='viewport' content='width=device-width, initial-scale=1'>\n"
        "<title>__CE_TITLE__</title>\n<style>\n"
        + asset(STYLE)
        + "</style>\n</head>\n<body data-status='loading'>\n<pre id='errors' hidden></pre>\n"
        + "<script>\n"
        + asset(GUARD)
        + "</script>\n"
        + BODY
        + "<script type='application/json' id='ce-data'>__CE_DATA__</script>\n<script>\n"
        + script()
        + "</script>\n</body>\n</html>\n"
    )


# Per-sample series are embedded as integer deltas between consecutive samples (a third of the
# size of decimal text): value = (sum of the deltas so far, per stride position) / scale.
POSITION_SCALE = 10_000  # 0.1 mm (replay_data rounds positions to it already)
JOINT_SCALE = 100_000  # 1e-5 rad, rad/s
TIME_SCALE = 10_000  # 0.1 ms


def pack(values: Sequence[float], stride: int, scale: int) -> dict[str, Any]:
    """A flat series of ``stride`` numbers per sample as integer deltas along the samples."""
    a = np.rint(np.asarray(values, dtype=float).reshape(-1, stride) * scale).astype(np.int64)
    delta = np.vstack([a[:1], np.diff(a, axis=0)]) if len(a) else a
    return {"scale": scale, "stride": stride, "delta": delta.ravel().tolist()}


def unpack(packed: Mapping[str, Any]) -> NDArray[np.float64]:
    """Inverse of :func:`pack` (what the page does at load), flat."""
    stride, scale = int(packed["stride"]), float(packed["scale"])
    delta = np.asarray(packed["delta"], dtype=np.int64).reshape(-1, stride)
    return (np.cumsum(delta, axis=0) / scale).ravel()


def pack_replay(replay: Mapping[str, Any]) -> dict[str, Any]:
    """``replay`` with its per-sample series packed (static meshes stay as they are)."""
    out = dict(replay)
    out["times"] = pack(replay["times"], 1, TIME_SCALE)
    out["q"] = [pack(s, 1, JOINT_SCALE) for s in replay["q"]]
    out["qd"] = [pack(s, 1, JOINT_SCALE) for s in replay["qd"]]
    out["tcp"] = {arm: pack(v, 3, POSITION_SCALE) for arm, v in replay["tcp"].items()}
    out["links"] = [
        {**link, "points": pack(link["points"], link["stride"], POSITION_SCALE)}
        for link in replay["links"]
    ]
    out["objects"] = [
        {**o, "points": pack(o["points"], o["stride"], POSITION_SCALE)}
        for o in replay.get("objects", [])
    ]
    if replay.get("arm_distance") is not None:
        out["arm_distance"] = pack(replay["arm_distance"], 1, POSITION_SCALE)
    return out


def embed_json(data: Any) -> str:
    """JSON safe inside a <script> element: '<' written as \\u003c, so no '</script>' or
    '<!--' can appear; strict (no NaN)."""
    text = json.dumps(data, separators=(",", ":"), allow_nan=False, ensure_ascii=False)
    return text.replace("<", "\\u003c").replace("\u2028", "\\u2028").replace("\u2029", "\\u2029")


def render_page(report: Mapping[str, Any], replay: Mapping[str, Any], title: str) -> str:
    data = embed_json({"report": report, "replay": pack_replay(replay), "title": title})
    head, _, tail = template().partition("__CE_DATA__")
    return head.replace("__CE_TITLE__", html.escape(title)) + data + tail
