// report.html's script (see base.js): the moments of least clearance (report.json's totals:
// between the arms, and to the environment; else the least distance between the arms), marked
// on the plots and drawn in the 3D view: the pair's shapes outlined, joined by a line with the
// distance, while the segment of that moment plays.
/* global css, ctx, DUR, fmt, isNum, linkAt, NEAR, partName, project, RE, RP, state, statics, T */
/* exported closestMarks, drawClosest, drawMarks */

const CLOSEST_COLOR = '#dc2626';
const CLOSEST = (function () {
  const c = (RE.totals || {}).clearance || {};
  const out = [];
  for (const kind of ['arms', 'environment']) {
    const m = c[kind];
    if (!m || !isNum(m.time_s)) continue;
    const seg = RE.segments[m.segment] || {};
    out.push({ kind, time: m.time_s, pair: m.pair || [], d: m.distance_m,
      start: isNum(seg.start_s) ? seg.start_s : m.time_s, end: isNum(seg.end_s) ? seg.end_s : m.time_s });
  }
  if (!out.length && RP.segments.length && RP.arm_distance && RP.arm_distance.length) {
    let k = 0;
    RP.arm_distance.forEach((d, i) => { if (d < RP.arm_distance[k]) k = i; });
    const pair = (RE.totals || {}).closest_pair || [];
    out.push({ kind: 'arms', time: T[k], pair, d: RP.arm_distance[k], start: T[k], end: T[k] });
  }
  return out;
})();
function closestMarks() {
  return CLOSEST.map((m) => ({ time: m.time, d: m.d, label: 'least ' + m.kind + ' clearance ' +
    fmt(1000 * m.d, 1, 'mm') }));
}
// vertical dashed lines with their labels on a plot's canvas (x of a time by xOf)
function drawMarks(g, marks, xOf, top, bottom) {
  g.save();
  g.strokeStyle = CLOSEST_COLOR; g.fillStyle = CLOSEST_COLOR;
  g.setLineDash([2, 3]); g.lineWidth = 1.2;
  g.font = '10px system-ui, sans-serif'; g.textAlign = 'left'; g.textBaseline = 'top';
  (marks || []).forEach((m, k) => {
    const x = xOf(m.time);
    g.beginPath(); g.moveTo(x, top); g.lineTo(x, bottom); g.stroke();
    g.fillText('\u25bc ' + m.label, x + 3, top + 1 + 11 * k);
  });
  g.restore();
}
// a shape's centre and its points for an outline: an arm link or a static mesh, by name
function shapeOf(name, i, f) {
  const link = RP.links.find((l) => l.name === name) ||
    RP.objects.find((o) => o.name === name.split('@')[0]);
  if (link) {
    const p = linkAt(link, i, f);
    const two = link.kind === 'capsule' || link.kind === 'cylinder';
    const c = two ? [(p[0] + p[3]) / 2, (p[1] + p[4]) / 2, (p[2] + p[5]) / 2] : p.slice(0, 3);
    return { c, pts: two ? [p.slice(0, 3), p.slice(3, 6)] : [c] };
  }
  const s = statics.find((x) => x.name === name || x.name === name.replace(/#\d+$/, ''));
  if (!s) return null;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let k = 0; k < s.v.length; k += 3) {
    for (let a = 0; a < 3; a++) {
      lo[a] = Math.min(lo[a], s.v[k + a]); hi[a] = Math.max(hi[a], s.v[k + a]);
    }
  }
  return { c: lo.map((v, a) => (v + hi[a]) / 2), pts: [], lo, hi };
}
// the pair's two points: a static's is the point of its bounds nearest the other's centre
// (the table under a gripper, not the table's middle)
function pairPoints(shapes) {
  return shapes.map((s, k) => {
    if (!s.lo) return s.c;
    const o = shapes[1 - k].c;
    return o.map((v, a) => Math.min(s.hi[a], Math.max(s.lo[a], v)));
  });
}
function drawClosest(V, i, f) {
  const pad = 0.02 * DUR;
  for (const m of CLOSEST) {
    if (state.t < m.start - pad || state.t > m.end + pad || m.pair.length !== 2) continue;
    const shapes = m.pair.map((n) => shapeOf(n, i, f));
    if (shapes.some((s) => !s)) continue;
    ctx.strokeStyle = css([220, 38, 38], 1, 0.9); ctx.fillStyle = CLOSEST_COLOR;
    ctx.lineWidth = 2; ctx.setLineDash([5, 4]);
    const ends = pairPoints(shapes).map((c) => project(V, c[0], c[1], c[2]));
    if (ends.some((q) => q[2] < NEAR)) { ctx.setLineDash([]); continue; }
    ctx.beginPath(); ctx.moveTo(ends[0][0], ends[0][1]); ctx.lineTo(ends[1][0], ends[1][1]);
    ctx.stroke(); ctx.setLineDash([]);
    for (const s of shapes) {
      for (const p of s.pts) {
        const q = project(V, p[0], p[1], p[2]);
        if (q[2] < NEAR) continue;
        ctx.beginPath(); ctx.arc(q[0], q[1], 5, 0, 2 * Math.PI); ctx.stroke();
      }
    }
    const x = (ends[0][0] + ends[1][0]) / 2;
    const y = (ends[0][1] + ends[1][1]) / 2;
    ctx.font = '600 12px system-ui, sans-serif';
    ctx.fillText(fmt(1000 * m.d, 1, 'mm') + ' ' + m.pair.map(partName).join(' \u2194 ') +
      (Math.abs(state.t - m.time) < pad ? '' : ' (at ' + fmt(m.time, 2, 's') + ')'), x + 6, y - 6);
  }
}
