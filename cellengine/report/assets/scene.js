// report.html's script (see base.js): the 3D scene; the orbiting camera and its projection,
// the static meshes as shaded triangles, the arms' links at a time, cables and fingertips.
/* global $, armColor, css, FAIL_COLOR, failureColor, FOV, GROUP_COLORS, linkAt, mix, NEAR, rgb,
   RP, state, tcpAt */
/* exported addKeypoints, addLinks, addShape, addStatic, sceneBounds, drawCables, handsAt,
   makeView, resetCamera,
   statics */

// ---------------------------------------------------------------- camera
const canvas = $('view');
const ctx = canvas.getContext('2d');
const cam = { az: 0, el: 0, dist: 2, target: [0, 0, 0] };

function sceneBounds() {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  const add = (x, y, z) => {
    const p = [x, y, z];
    for (let k = 0; k < 3; k++) { lo[k] = Math.min(lo[k], p[k]); hi[k] = Math.max(hi[k], p[k]); }
  };
  for (const s of RP.static) {
    if (s.ground) continue;
    const v = s.vertices;
    for (let k = 0; k < v.length; k += 3) add(v[k], v[k + 1], v[k + 2]);
  }
  for (const l of RP.links) {
    add(l.points[0], l.points[1], l.points[2]);
    if (l.kind === 'capsule' || l.kind === 'cylinder') add(l.points[3], l.points[4], l.points[5]);
  }
  // the arms where they start (their whole paths may reach far out of the work area)
  for (const arm of RP.arms) add(RP.tcp[arm][0], RP.tcp[arm][1], RP.tcp[arm][2]);
  if (!isFinite(lo[0])) return [[-0.5, -0.5, 0], [0.5, 0.5, 0.5]];
  return [lo, hi];
}
function resetCamera() {
  const [lo, hi] = sceneBounds();
  cam.target = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
  const radius = 0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  cam.dist = Math.max(0.3, 0.85 * radius / Math.sin(FOV / 2));
  cam.az = -0.75; // from the front, on the right arm's side: the platforms before the arms
  cam.el = 0.55;
}
function makeView(w, h) {
  const ce = Math.cos(cam.el);
  const back = [ce * Math.cos(cam.az), ce * Math.sin(cam.az), Math.sin(cam.el)];
  const eye = [0, 1, 2].map((k) => cam.target[k] + back[k] * cam.dist);
  const f = [-back[0], -back[1], -back[2]];
  const rl = Math.hypot(f[0], f[1]) || 1;
  const r = [f[1] / rl, -f[0] / rl, 0];
  const u = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]];
  const l = [0, 1, 2].map((k) => -0.55 * f[k] + 0.7 * u[k] - 0.45 * r[k]);
  const ln = Math.hypot(l[0], l[1], l[2]);
  return { eye, f, r, u, focal: (h / 2) / Math.tan(FOV / 2), cx: w / 2, cy: h / 2,
    light: l.map((x) => x / ln) };
}
function project(V, x, y, z) {
  const dx = x - V.eye[0];
  const dy = y - V.eye[1];
  const dz = z - V.eye[2];
  const zc = dx * V.f[0] + dy * V.f[1] + dz * V.f[2];
  const xc = dx * V.r[0] + dy * V.r[1] + dz * V.r[2];
  const yc = dx * V.u[0] + dy * V.u[1] + dz * V.u[2];
  return [V.cx + V.focal * xc / zc, V.cy - V.focal * yc / zc, zc];
}
function lambert(V, n) {
  return Math.abs(n[0] * V.light[0] + n[1] * V.light[1] + n[2] * V.light[2]);
}

// ---------------------------------------------------------------- static meshes
const groups = [...new Set(RP.static.filter((s) => s.kind === 'element').map((s) => s.group))];
const statics = RP.static.map((s) => {
  const v = s.vertices;
  const tr = s.triangles;
  const normals = new Float64Array(tr.length);
  for (let t = 0; t < tr.length; t += 3) {
    const a = tr[t] * 3;
    const b = tr[t + 1] * 3;
    const c = tr[t + 2] * 3;
    const e1 = [v[b] - v[a], v[b + 1] - v[a + 1], v[b + 2] - v[a + 2]];
    const e2 = [v[c] - v[a], v[c + 1] - v[a + 1], v[c + 2] - v[a + 2]];
    const n = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
      e1[0] * e2[1] - e1[1] * e2[0]];
    const len = Math.hypot(n[0], n[1], n[2]) || 1;
    normals[t] = n[0] / len; normals[t + 1] = n[1] / len; normals[t + 2] = n[2] / len;
  }
  let color = rgb(GROUP_COLORS[groups.indexOf(s.group) % GROUP_COLORS.length] || '#8a94a6');
  if (s.kind === 'obstacle') color = rgb(s.ground ? '#d3d9e2' : '#aab3c0');
  return { name: s.name, ground: s.ground, v, tr, normals, color,
    pv: new Float64Array(v.length) };
});

function addStatic(V, s, out) {
  const color = failureColor(s.name) || s.color;
  const v = s.v;
  const pv = s.pv;
  const tr = s.tr;
  const n = s.normals;
  for (let k = 0; k < v.length; k += 3) {
    const p = project(V, v[k], v[k + 1], v[k + 2]);
    pv[k] = p[0]; pv[k + 1] = p[1]; pv[k + 2] = p[2];
  }
  for (let t = 0; t < tr.length; t += 3) {
    const a = tr[t] * 3;
    const b = tr[t + 1] * 3;
    const c = tr[t + 2] * 3;
    if (pv[a + 2] < NEAR || pv[b + 2] < NEAR || pv[c + 2] < NEAR) continue;
    const lam = lambert(V, [n[t], n[t + 1], n[t + 2]]);
    out.push({ type: 'poly', wire: state.wire, z: (pv[a + 2] + pv[b + 2] + pv[c + 2]) / 3,
      pts: [pv[a], pv[a + 1], pv[b], pv[b + 1], pv[c], pv[c + 1]],
      fill: css(color, 0.62 + 0.45 * lam) });
  }
}

// ---------------------------------------------------------------- moving shapes
// the links at sample i + f of the replay, or ``links`` (each one sample: a failing pose, its
// pair highlighted and drawn over everything: seen through what stands before it)
function addLinks(V, i, f, out, links) {
  for (const link of links || RP.links) {
    const start = out.length;
    const own = rgb(armColor[link.arm] || '#777777');
    let color = /\/tool(#\d+)?$/.test(link.name) ? mix(own, [55, 60, 70], 0.6) : own;
    if (link.highlight) color = FAIL_COLOR;
    addShape(V, link, linkAt(link, i, f), color, out);
    if (link.highlight) for (let k = start; k < out.length; k++) out[k].z *= 1e-3;
  }
}
// a link-like shape (replay.py's layout) at its points p; round: a cylinder drawn capsule-ended
function addShape(V, link, p, color, out, round) {
  if (link.kind === 'capsule' || link.kind === 'cylinder') {
    const a = project(V, p[0], p[1], p[2]);
    const b = project(V, p[3], p[4], p[5]);
    if (a[2] < NEAR || b[2] < NEAR) return;
    const z = (a[2] + b[2]) / 2;
    out.push({ type: 'cap', z, ax: a[0], ay: a[1], bx: b[0] + 0.01, by: b[1],
      w: 2 * link.radius * V.focal / z, color, round: round || link.kind === 'capsule' });
  } else if (link.kind === 'sphere') {
    const c = project(V, p[0], p[1], p[2]);
    if (c[2] < NEAR) return;
    out.push({ type: 'ball', z: c[2], x: c[0], y: c[1], r: link.radius * V.focal / c[2],
      color });
  } else {
    addBox(V, p, color, out);
  }
}
function addBox(V, p, color, out) {
  const c = [p[0], p[1], p[2]];
  const ax = [[p[3], p[4], p[5]], [p[6], p[7], p[8]], [p[9], p[10], p[11]]];
  for (let k = 0; k < 3; k++) {
    for (const sg of [1, -1]) {
      const a = ax[k];
      const m = ax[(k + 1) % 3];
      const n = ax[(k + 2) % 3];
      const corners = [[1, 1], [1, -1], [-1, -1], [-1, 1]].map(([s1, s2]) => project(V,
        c[0] + sg * a[0] + s1 * m[0] + s2 * n[0],
        c[1] + sg * a[1] + s1 * m[1] + s2 * n[1],
        c[2] + sg * a[2] + s1 * m[2] + s2 * n[2]));
      if (corners.some((q) => q[2] < NEAR)) continue;
      const len = Math.hypot(a[0], a[1], a[2]) || 1;
      const lam = lambert(V, [a[0] / len, a[1] / len, a[2] / len]);
      out.push({ type: 'poly', z: corners.reduce((s, q) => s + q[2], 0) / 4,
        pts: corners.flatMap((q) => [q[0], q[1]]), fill: css(color, 0.6 + 0.5 * lam) });
    }
  }
}
function handsAt(i, f) {
  const tcp = {};
  for (const arm of RP.arms) tcp[arm] = tcpAt(arm, i, f);
  return tcp;
}
// a cable at time t: through the slots it has been placed in so far, then the hands holding
// it (the hand nearer the last slot first)
function cablePath(c, tcp) {
  const t = state.t;
  const pts = c.anchors.filter((a) => a.time <= t + 1e-9).map((a) => a.p);
  let span = null;
  for (const h of c.held) if (h.start <= t + 1e-9 && t <= h.end + 1e-9) span = h;
  const hands = span ? span.arms.map((a) => tcp[a]).filter(Boolean) : [];
  if (hands.length === 2 && pts.length) {
    const last = pts[pts.length - 1];
    const d = (p) => Math.hypot(p[0] - last[0], p[1] - last[1], p[2] - last[2]);
    if (d(hands[1]) < d(hands[0])) hands.reverse();
  }
  return [pts, pts.concat(hands)];
}
// point j of the screen polyline q moved by d pixels across it (its neighbours' normal)
function offsetAt(q, j, d) {
  if (!d) return q[j];
  const a = q[Math.max(0, j - 1)], b = q[Math.min(q.length - 1, j + 1)];
  const len = Math.hypot(b[0] - a[0], b[1] - a[1]) || 1;
  return [q[j][0] - d * (b[1] - a[1]) / len, q[j][1] + d * (b[0] - a[0]) / len, q[j][2]];
}
// drawn over everything: the cable and the fingertips are what the replay is about
function drawCables(V, tcp) {
  let count = 0;
  ctx.lineCap = 'round';
  ctx.lineJoin = 'round';
  for (const c of RP.cables) {
    const [anchors, path] = cablePath(c, tcp);
    const q = path.map((p) => project(V, p[0], p[1], p[2]));
    if (path.length < 2 || q.some((p) => p[2] < NEAR)) continue;
    const z = q.reduce((sum, p) => sum + p[2], 0) / q.length;
    const stroke = () => {
      ctx.beginPath();
      q.forEach((p, k) => (k ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
      ctx.stroke();
    };
    const members = c.members && c.members.length ? c.members : [{ color: null }];
    const w = Math.max(3, 0.006 * V.focal / z);
    const inner = Math.max(1, 0.3 * w);
    ctx.strokeStyle = '#111827'; ctx.lineWidth = w + inner * (members.length - 1); stroke();
    // each cable of a group in its own colour, side by side across the line
    members.forEach((m, k) => {
      const shift = (k - (members.length - 1) / 2) * inner;
      const moved = q.map((p, j) => offsetAt(q, j, shift));
      ctx.beginPath();
      moved.forEach((p, j) => (j ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
      ctx.strokeStyle = m.color || '#8b95a5'; ctx.lineWidth = inner; ctx.stroke();
    });
    for (let k = 0; k < anchors.length; k++) {
      ctx.beginPath(); ctx.arc(q[k][0], q[k][1], 3, 0, 2 * Math.PI);
      ctx.fillStyle = '#facc15'; ctx.fill();
      ctx.strokeStyle = '#111827'; ctx.lineWidth = 1.2; ctx.stroke();
    }
    count += 1;
  }
  for (const arm of RP.arms) {
    const q = project(V, tcp[arm][0], tcp[arm][1], tcp[arm][2]);
    if (q[2] < NEAR) continue;
    ctx.beginPath(); ctx.arc(q[0], q[1], 3.5, 0, 2 * Math.PI);
    ctx.fillStyle = '#ffffff'; ctx.fill();
    ctx.strokeStyle = armColor[arm]; ctx.lineWidth = 2; ctx.stroke();
  }
  return count;
}
function addKeypoints(V, out) {
  for (const kp of RP.keypoints) {
    const q = project(V, kp.p[0], kp.p[1], kp.p[2]);
    if (q[2] < NEAR) continue;
    out.push({ type: 'dot', z: q[2] - 0.02, x: q[0], y: q[1], r: 2.2, fill: '#334155',
      stroke: null });
  }
}
