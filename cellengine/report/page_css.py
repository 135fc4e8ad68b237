"""report.html's style sheet (inlined; system fonts only, nothing fetched)."""

CSS = r"""
:root {
  --bg: #f3f5f8; --panel: #ffffff; --ink: #1f2933; --muted: #66748a; --line: #e1e6ee;
  --accent: #2563eb; --ok: #047857; --bad: #b91c1c; --head: #111827;
}
* { box-sizing: border-box; }
html, body { margin: 0; }
body {
  font: 13px/1.45 system-ui, -apple-system, "Segoe UI", Roboto, Helvetica, Arial, sans-serif;
  background: var(--bg); color: var(--ink);
}
header {
  display: flex; align-items: center; gap: 16px; flex-wrap: wrap;
  padding: 10px 18px; background: var(--head); color: #f9fafb;
}
header h1 { font-size: 15px; margin: 0; font-weight: 600; letter-spacing: .01em; }
header .sub { color: #9ca3af; font-size: 12px; }
.chips { display: flex; gap: 6px; flex-wrap: wrap; margin-left: auto; }
.chip {
  background: rgba(255, 255, 255, .09); border-radius: 999px; padding: 2px 10px;
  font-size: 12px; white-space: nowrap;
}
.chip b { font-weight: 600; }
.chip.ok { background: #065f46; } .chip.bad { background: #991b1b; }
.wrap { padding: 12px 18px 24px; display: grid; gap: 12px; }
.row1 { display: grid; grid-template-columns: minmax(0, 1fr) 330px; gap: 12px; }
@media (max-width: 1000px) { .row1 { grid-template-columns: minmax(0, 1fr); } }
.panel {
  background: var(--panel); border: 1px solid var(--line); border-radius: 8px;
  padding: 10px 12px; min-width: 0;
}
.panel h2 {
  font-size: 11px; text-transform: uppercase; letter-spacing: .07em; color: var(--muted);
  margin: 0 0 8px; font-weight: 600;
}
#view-wrap { position: relative; height: 540px; border-radius: 6px; overflow: hidden; }
#view { width: 100%; height: 100%; display: block; cursor: grab; touch-action: none; }
#view.dragging { cursor: grabbing; }
.hud {
  position: absolute; pointer-events: none; font-size: 12px; background: rgba(255,255,255,.86);
  border-radius: 6px; padding: 5px 8px; box-shadow: 0 1px 2px rgba(0,0,0,.08);
}
#hud-step { left: 10px; top: 10px; max-width: 60%; }
#hud-step .lbl { font-weight: 600; }
#hud-help { right: 10px; bottom: 10px; color: var(--muted); font-size: 11px; }
#hud-legend { left: 10px; bottom: 10px; display: flex; gap: 10px; align-items: center; }
.dot { display: inline-block; width: 10px; height: 10px; border-radius: 50%; margin-right: 4px;
  vertical-align: -1px; }
.controls { display: flex; align-items: center; gap: 8px; margin-top: 8px; flex-wrap: wrap; }
.controls input[type=range] { flex: 1; min-width: 100px; accent-color: var(--accent); }
button, select {
  font: inherit; border: 1px solid var(--line); background: #fff; color: var(--ink);
  border-radius: 6px; padding: 3px 10px; cursor: pointer;
}
button:hover, select:hover { border-color: #b9c3d3; }
button.on { background: #e8efff; border-color: #b6c8f5; }
#play { width: 74px; background: var(--accent); color: #fff; border-color: var(--accent); }
#clock { font-variant-numeric: tabular-nums; white-space: nowrap; }
.kv { display: grid; grid-template-columns: auto 1fr; gap: 2px 10px; margin: 0; }
.kv dt { color: var(--muted); }
.kv dd { margin: 0; font-variant-numeric: tabular-nums; overflow-wrap: anywhere; }
.now + .now { margin-top: 10px; padding-top: 10px; border-top: 1px solid var(--line); }
table { border-collapse: collapse; width: 100%; }
th, td { padding: 3px 6px; border-bottom: 1px solid var(--line); text-align: left;
  vertical-align: top; }
th { color: var(--muted); font-weight: 600; font-size: 11px; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; white-space: nowrap; }
table.joints td, table.joints th { padding: 1px 4px; font-size: 12px; }
#timeline { position: relative; user-select: none; }
.lane { position: relative; height: 24px; margin-bottom: 4px; background: #f6f8fb;
  border-radius: 4px; cursor: pointer; }
.lane.thin { height: 14px; }
.lane.events { height: 16px; background: none; }
.lane-name { font-size: 11px; color: var(--muted); margin: 2px 0; }
.bar {
  position: absolute; top: 0; bottom: 0; border-radius: 4px; overflow: hidden;
  white-space: nowrap; text-overflow: ellipsis; font-size: 11px; line-height: 24px;
  padding: 0 6px; color: #fff; border-right: 1px solid #fff;
}
.lane.thin .bar { line-height: 14px; font-size: 10px; padding: 0 3px; border-radius: 2px; }
.bar.active { box-shadow: inset 0 0 0 2px rgba(17, 24, 39, .75); }
.tick { position: absolute; top: 2px; width: 0; height: 0; border-left: 5px solid transparent;
  border-right: 5px solid transparent; border-top: 10px solid #333; margin-left: -5px; }
#tl-cursor { position: absolute; top: 0; bottom: 0; width: 2px; background: #ef4444;
  pointer-events: none; margin-left: -1px; }
.axis { position: relative; height: 16px; font-size: 10px; color: var(--muted); }
.axis span { position: absolute; transform: translateX(-50%); white-space: nowrap; }
.axis span:last-child { transform: translateX(-100%); }
.axis span:first-child { transform: none; }
.plots { display: grid; grid-template-columns: repeat(auto-fit, minmax(380px, 1fr)); gap: 12px; }
.plot-title { display: flex; justify-content: space-between; flex-wrap: wrap; gap: 0 10px;
  font-size: 12px; margin: 6px 0 2px; }
.plot-title span:last-child { color: var(--muted); }
canvas.plot { width: 100%; height: 130px; display: block; cursor: crosshair; }
.legend { display: flex; flex-wrap: wrap; gap: 2px 10px; font-size: 11px; color: var(--muted);
  margin-top: 4px; }
tr.step-row td { background: #f6f8fb; font-weight: 600; }
tr.clickable { cursor: pointer; }
tr.clickable:hover td { background: #eef3ff; }
tr.active td { background: #e3ecff !important; }
td.pass { color: var(--ok); font-weight: 600; } td.fail { color: var(--bad); font-weight: 600; }
td.indent { padding-left: 22px; }
td.nowrap { white-space: nowrap; }
.muted { color: var(--muted); }
#errors { margin: 0; padding: 10px 18px; color: #991b1b; background: #fef2f2;
  border-bottom: 1px solid #fecaca; white-space: pre-wrap; }
pre.json { margin: 0; font-size: 11px; white-space: pre-wrap; overflow-wrap: anywhere; }
"""
