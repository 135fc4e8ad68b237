// report.html's script (see base.js): drawing the 3D view; shapes back to front (painter's
// algorithm), the ground grid, fingertip paths, axes and arm labels.
/* global addKeypoints, addLinks, addObjects, addStatic, armColor, BG, cam, canvas, css, ctx,
   drawCables, drawClosest, drawKeyLabels, drawObjectLabels, drawZones, failurePose, handsAt,
   lastStarted, locate, makeView, markFailure, mix, N, NEAR, project, rgb, RP, state, statics,
   WHITE */
/* exported drawView */
/* global drawReach */

// ---------------------------------------------------------------- drawing
function fitCanvas(c, g) {
  const r = c.getBoundingClientRect();
  const d = window.devicePixelRatio || 1;
  const w = Math.max(1, Math.round(r.width));
  const h = Math.max(1, Math.round(r.height));
  if (c.width !== Math.round(w * d) || c.height !== Math.round(h * d)) {
    c.width = Math.round(w * d);
    c.height = Math.round(h * d);
  }
  g.setTransform(d, 0, 0, d, 0, 0);
  return [w, h];
}
function segment(g, ax, ay, bx, by) {
  g.beginPath(); g.moveTo(ax, ay); g.lineTo(bx, by); g.stroke();
}
function drawPrim(p) {
  if (p.type === 'poly') {
    ctx.beginPath();
    ctx.moveTo(p.pts[0], p.pts[1]);
    for (let k = 2; k < p.pts.length; k += 2) ctx.lineTo(p.pts[k], p.pts[k + 1]);
    ctx.closePath();
    if (p.wire) {
      ctx.strokeStyle = p.fill; ctx.lineWidth = 0.8; ctx.stroke();
    } else {
      ctx.fillStyle = p.fill; ctx.fill();
      ctx.strokeStyle = p.fill; ctx.lineWidth = 0.6; ctx.stroke();
    }
  } else if (p.type === 'cap') {
    ctx.lineCap = p.round ? 'round' : 'butt';
    ctx.strokeStyle = css(p.color, 0.5); ctx.lineWidth = p.w + 1.5;
    segment(ctx, p.ax, p.ay, p.bx, p.by);
    ctx.strokeStyle = css(p.color, 0.95); ctx.lineWidth = p.w;
    segment(ctx, p.ax, p.ay, p.bx, p.by);
    const o = p.w * 0.12;
    ctx.strokeStyle = css(mix(p.color, WHITE, 0.45), 1); ctx.lineWidth = p.w * 0.34;
    segment(ctx, p.ax - o, p.ay - o, p.bx - o, p.by - o);
  } else if (p.type === 'ball') {
    const r = Math.max(p.r, 0.5);
    const g = ctx.createRadialGradient(p.x - r * 0.35, p.y - r * 0.35, r * 0.1, p.x, p.y, r);
    g.addColorStop(0, css(mix(p.color, WHITE, 0.5), 1));
    g.addColorStop(1, css(p.color, 0.7));
    ctx.fillStyle = g;
    ctx.beginPath(); ctx.arc(p.x, p.y, r, 0, 2 * Math.PI); ctx.fill();
  } else if (p.type === 'dot') {
    ctx.beginPath(); ctx.arc(p.x, p.y, p.r, 0, 2 * Math.PI);
    ctx.fillStyle = p.fill; ctx.fill();
    if (p.stroke) { ctx.strokeStyle = p.stroke; ctx.lineWidth = 2; ctx.stroke(); }
  }
}
function drawGrid(V) {
  const ground = statics.filter((s) => s.ground);
  let lo = [cam.target[0] - 1, cam.target[1] - 1];
  let hi = [cam.target[0] + 1, cam.target[1] + 1];
  let z = 0;
  if (ground.length) {
    lo = [Infinity, Infinity]; hi = [-Infinity, -Infinity]; z = -Infinity;
    for (const s of ground) {
      for (let k = 0; k < s.v.length; k += 3) {
        lo = [Math.min(lo[0], s.v[k]), Math.min(lo[1], s.v[k + 1])];
        hi = [Math.max(hi[0], s.v[k]), Math.max(hi[1], s.v[k + 1])];
        z = Math.max(z, s.v[k + 2]);
      }
    }
  }
  z += 0.0005;
  const step = 0.1;
  ctx.lineWidth = 1;
  for (let axis = 0; axis < 2; axis++) {
    for (let c = Math.ceil(lo[axis] / step) * step; c <= hi[axis] + 1e-9; c += step) {
      const major = Math.abs(c / 0.5 - Math.round(c / 0.5)) < 1e-6;
      const other = 1 - axis;
      const p = [0, 0];
      const q = [0, 0];
      p[axis] = c; q[axis] = c; p[other] = lo[other]; q[other] = hi[other];
      const a = project(V, p[0], p[1], z);
      const b = project(V, q[0], q[1], z);
      if (a[2] < NEAR || b[2] < NEAR) continue;
      ctx.strokeStyle = major ? 'rgba(70,84,110,0.28)' : 'rgba(70,84,110,0.12)';
      segment(ctx, a[0], a[1], b[0], b[1]);
    }
  }
}
function polyline(V, a, i0, i1) {
  ctx.beginPath();
  let pen = false;
  for (let i = i0; i <= i1; i++) {
    const p = project(V, a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    if (p[2] < NEAR) { pen = false; continue; }
    if (pen) ctx.lineTo(p[0], p[1]); else { ctx.moveTo(p[0], p[1]); pen = true; }
  }
  ctx.stroke();
}
function drawTrails(V) {
  const step = lastStarted(RP.steps, state.t);
  ctx.lineCap = 'round';
  ctx.lineJoin = 'round';
  for (const arm of RP.arms) {
    const c = rgb(armColor[arm]);
    ctx.strokeStyle = css(c, 1, 0.22); ctx.lineWidth = 1.2;
    polyline(V, RP.tcp[arm], 0, N - 1);
    if (step) {
      const i0 = locate(step.start)[0];
      const [i1, f1] = locate(step.end);
      ctx.strokeStyle = css(c, 0.9, 0.75); ctx.lineWidth = 2;
      polyline(V, RP.tcp[arm], i0, Math.min(N - 1, i1 + (f1 > 0 ? 1 : 0)));
    }
  }
}
function drawAxes(V) {
  const o = project(V, 0, 0, 0);
  if (o[2] < NEAR) return;
  const names = ['x', 'y', 'z'];
  const colors = ['#dc2626', '#16a34a', '#2563eb'];
  ctx.lineCap = 'round';
  ctx.font = '600 11px system-ui, sans-serif';
  for (let k = 0; k < 3; k++) {
    const e = [0, 0, 0];
    e[k] = 0.1;
    const p = project(V, e[0], e[1], e[2]);
    if (p[2] < NEAR) continue;
    ctx.strokeStyle = colors[k]; ctx.lineWidth = 2.5;
    segment(ctx, o[0], o[1], p[0], p[1]);
    ctx.fillStyle = colors[k];
    ctx.fillText(names[k], p[0] + 3, p[1] - 3);
  }
}
function drawArmLabels(V) {
  ctx.font = '600 12px system-ui, sans-serif';
  ctx.textAlign = 'center';
  for (const arm of RP.arms) {
    const base = RP.links.find((l) => l.arm === arm && l.fixed) ||
      RP.links.find((l) => l.arm === arm);
    if (!base) continue;
    const p = project(V, base.points[0], base.points[1], base.points[2] - 0.12);
    if (p[2] < NEAR) continue;
    ctx.fillStyle = armColor[arm];
    ctx.fillText(arm, p[0], p[1]);
  }
  ctx.textAlign = 'start';
}
function drawView() {
  const [w, h] = fitCanvas(canvas, ctx);
  ctx.fillStyle = BG;
  ctx.fillRect(0, 0, w, h);
  const V = makeView(w, h);
  const ground = [];
  const prims = [];
  for (const s of statics) addStatic(V, s, s.ground ? ground : prims);
  ground.sort((a, b) => b.z - a.z);
  for (const p of ground) drawPrim(p);
  drawGrid(V);
  drawZones(V);
  if (state.trails) drawTrails(V);
  const [i, f] = locate(state.t);
  const failing = failurePose(); // a failed plan's pose, shown instead of the replay's
  addLinks(V, i, f, prims, failing && failing.links);
  const before = prims.length;
  addObjects(V, i, f, prims);
  const objects = prims.length - before;
  if (state.keys) addKeypoints(V, prims);
  prims.sort((a, b) => b.z - a.z);
  for (const p of prims) drawPrim(p);
  const cables = drawCables(V, failing ? failing.tcp : handsAt(i, f));
  drawObjectLabels(V, i, f);
  const labels = state.keys ? drawKeyLabels(V) : 0;
  drawClosest(V, i, f);
  drawAxes(V);
  drawArmLabels(V);
  if (RP.reach) drawReach(V);
  const highlighted = failing ? markFailure(V, failing) : 0;
  return { shapes: ground.length + prims.length, cables, objects, labels, highlighted };
}
