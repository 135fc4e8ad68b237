'use strict';
(function () {
  const DATA = JSON.parse(document.getElementById('ce-data').textContent);
  const RP = DATA.replay;
  const RE = DATA.report;
  const $ = (id) => document.getElementById(id);

  // per-sample series come as integer deltas (see page.py's pack)
  function unpack(p) {
    if (!p || !p.delta) return p;
    const s = p.stride;
    const d = p.delta;
    const ints = new Float64Array(d.length);
    const out = new Float64Array(d.length);
    for (let i = 0; i < d.length; i++) {
      ints[i] = d[i] + (i >= s ? ints[i - s] : 0);
      out[i] = ints[i] / p.scale;
    }
    return out;
  }
  RP.times = unpack(RP.times);
  RP.q = RP.q.map(unpack);
  RP.qd = RP.qd.map(unpack);
  RP.arm_distance = unpack(RP.arm_distance);
  for (const arm of Object.keys(RP.tcp)) RP.tcp[arm] = unpack(RP.tcp[arm]);
  for (const link of RP.links) link.points = unpack(link.points);

  // ---------------------------------------------------------------- constants and helpers
  const ARM_COLORS = ['#2f6fdb', '#e0702a', '#0f9d58', '#9333ea'];
  const JOINT_COLORS = ['#2563eb', '#dc2626', '#059669', '#9333ea', '#ea580c', '#0891b2',
    '#ca8a04', '#db2777'];
  const GROUP_COLORS = ['#7f93b2', '#8fa37a', '#b89a6a', '#9284bd', '#5fa3a8'];
  const STEP_COLORS = ['#4f6d9a', '#5b8c6e', '#9a6b4f', '#7a5b9a', '#4f8a9a', '#9a4f6d'];
  const STRATEGY_COLORS = { split: '#64748b', sync: '#0e7490', async: '#a16207' };
  // the mission (lab plans): a robot's own work, and what the allocator inserted
  const MISSION_COLORS = { task: '#2563eb', handover: '#d97706', cooperation: '#7c3aed',
    obstacle: '#64748b' };
  const BG = '#e9edf3';
  const WHITE = [255, 255, 255];
  const FOV = 40 * Math.PI / 180;
  const NEAR = 0.02;
  const DASH = '\u2013';
  const armColor = {};
  RP.arms.forEach((a, i) => { armColor[a] = ARM_COLORS[i % ARM_COLORS.length]; });

  function rgb(hex) {
    const n = parseInt(hex.slice(1), 16);
    return [(n >> 16) & 255, (n >> 8) & 255, n & 255];
  }
  function css(c, k, a) {
    const f = (v) => Math.max(0, Math.min(255, Math.round(v * k)));
    const body = f(c[0]) + ',' + f(c[1]) + ',' + f(c[2]);
    return a === undefined ? 'rgb(' + body + ')' : 'rgba(' + body + ',' + a + ')';
  }
  function mix(c, d, w) {
    return [c[0] + (d[0] - c[0]) * w, c[1] + (d[1] - c[1]) * w, c[2] + (d[2] - c[2]) * w];
  }
  function isNum(x) { return typeof x === 'number' && isFinite(x); }
  function fmt(x, digits, unit) {
    if (!isNum(x)) return DASH;
    return x.toFixed(digits) + (unit ? ' ' + unit : '');
  }
  function el(tag, attrs, ...children) {
    const e = document.createElement(tag);
    for (const [k, v] of Object.entries(attrs || {})) {
      if (k === 'class') e.className = v;
      else if (k === 'style') e.style.cssText = v;
      else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
      else e.setAttribute(k, v);
    }
    for (const c of children) {
      if (c !== null && c !== undefined) e.append(c instanceof Node ? c : String(c));
    }
    return e;
  }
  function shortJoint(name, arm) {
    const s = name.startsWith(arm + '_') ? name.slice(arm.length + 1) : name;
    return s.replace(/_joint$/, '');
  }
  function capture(target, e) {
    try {
      target.setPointerCapture(e.pointerId);
    } catch (err) {
      // a synthetic or already released pointer: dragging works without capture
    }
  }
  function pairText(p) { return Array.isArray(p) ? p.join(' \u2194 ') : DASH; }
  function valueText(v) {
    if (v === null || v === undefined) return DASH;
    return typeof v === 'string' || typeof v === 'number' ? String(v) : JSON.stringify(v);
  }

  // ---------------------------------------------------------------- time and sampling
  const T = RP.times;
  const N = T.length;
  const T0 = RP.start;
  const T1 = RP.start + RP.duration;
  const DUR = Math.max(RP.duration, 1e-9);
  const state = { t: T0, playing: false, speed: 1, last: null,
    trails: true, keys: false, wire: false };
  RP.events.sort((a, b) => a.time - b.time);

  function clampT(t) { return Math.min(T1, Math.max(T0, t)); }
  function locate(t) {
    if (N === 1 || t <= T[0]) return [0, 0];
    if (t >= T[N - 1]) return [N - 1, 0];
    let lo = 0;
    let hi = N - 1;
    while (hi - lo > 1) {
      const m = (lo + hi) >> 1;
      if (T[m] <= t) lo = m; else hi = m;
    }
    return [lo, (t - T[lo]) / (T[hi] - T[lo])];
  }
  function at(arr, stride, k, i, f) {
    const a = arr[i * stride + k];
    return f === 0 ? a : a + (arr[(i + 1) * stride + k] - a) * f;
  }
  function seriesAt(arr, i, f) { return f === 0 ? arr[i] : arr[i] + (arr[i + 1] - arr[i]) * f; }
  function linkAt(link, i, f) {
    const s = link.stride;
    const out = new Array(s);
    for (let k = 0; k < s; k++) out[k] = link.fixed ? link.points[k] : at(link.points, s, k, i, f);
    return out;
  }
  function tcpAt(arm, i, f) {
    const a = RP.tcp[arm];
    return [at(a, 3, 0, i, f), at(a, 3, 1, i, f), at(a, 3, 2, i, f)];
  }
  function lastStarted(list, t) {
    let best = null;
    for (const s of list) if (s.start <= t + 1e-9) best = s;
    return best;
  }
  function grippersAt(t) {
    const g = {};
    for (const a of RP.arms) g[a] = null;
    for (const e of RP.events) if (e.time <= t + 1e-9) g[e.arm] = e;
    return g;
  }

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
        fill: css(s.color, 0.62 + 0.45 * lam) });
    }
  }

  // ---------------------------------------------------------------- moving shapes
  function addLinks(V, i, f, out) {
    for (const link of RP.links) {
      const p = linkAt(link, i, f);
      const own = rgb(armColor[link.arm] || '#777777');
      const color = /\/tool(#\d+)?$/.test(link.name) ? mix(own, [55, 60, 70], 0.6) : own;
      if (link.kind === 'capsule' || link.kind === 'cylinder') {
        const a = project(V, p[0], p[1], p[2]);
        const b = project(V, p[3], p[4], p[5]);
        if (a[2] < NEAR || b[2] < NEAR) continue;
        const z = (a[2] + b[2]) / 2;
        out.push({ type: 'cap', z, ax: a[0], ay: a[1], bx: b[0] + 0.01, by: b[1],
          w: 2 * link.radius * V.focal / z, color, round: link.kind === 'capsule' });
      } else if (link.kind === 'sphere') {
        const c = project(V, p[0], p[1], p[2]);
        if (c[2] < NEAR) continue;
        out.push({ type: 'ball', z: c[2], x: c[0], y: c[1], r: link.radius * V.focal / c[2],
          color });
      } else {
        addBox(V, p, color, out);
      }
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
      const w = Math.max(3, 0.006 * V.focal / z);
      ctx.strokeStyle = '#111827'; ctx.lineWidth = w; stroke();
      ctx.strokeStyle = '#8b95a5'; ctx.lineWidth = Math.max(1, 0.3 * w); stroke();
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
    if (state.trails) drawTrails(V);
    const [i, f] = locate(state.t);
    addLinks(V, i, f, prims);
    if (state.keys) addKeypoints(V, prims);
    prims.sort((a, b) => b.z - a.z);
    for (const p of prims) drawPrim(p);
    const cables = drawCables(V, handsAt(i, f));
    drawAxes(V);
    drawArmLabels(V);
    return { shapes: ground.length + prims.length, cables };
  }

  // ---------------------------------------------------------------- plots
  function niceTicks(lo, hi, count) {
    if (!(hi > lo)) return { ticks: [lo], digits: 0 };
    const raw = (hi - lo) / Math.max(1, count);
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-6; v += step) {
      out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
    }
    return { ticks: out, digits: Math.max(0, -Math.floor(Math.log10(step) + 1e-9)) };
  }
  const plots = [];
  function makePlot(parent, title, info, lines, opts) {
    parent.append(el('div', { class: 'plot-title' }, el('span', {}, title),
      el('span', {}, info)));
    const cv = el('canvas', { class: 'plot' });
    parent.append(cv);
    const g = cv.getContext('2d');
    let lo = Infinity;
    let hi = -Infinity;
    for (const l of lines) for (const v of l.values) { if (v < lo) lo = v; if (v > hi) hi = v; }
    if (!isFinite(lo)) { lo = -1; hi = 1; }
    if (opts.symmetric) {
      const m = Math.max(Math.abs(lo), Math.abs(hi), opts.minSpan || 0);
      lo = -m; hi = m;
    }
    for (const b of opts.include || []) { lo = Math.min(lo, b); hi = Math.max(hi, b); }
    if (hi - lo < 1e-9) { lo -= 0.5; hi += 0.5; }
    const pad = (hi - lo) * 0.08;
    lo -= pad; hi += pad;
    const M = { l: 46, r: 8, t: 6, b: 18 };
    const xOf = (t, w) => M.l + (t - T0) / DUR * (w - M.l - M.r);
    const yOf = (v, h) => M.t + (hi - v) / (hi - lo) * (h - M.t - M.b);
    let base = null;
    let size = '';
    function renderBase(w, h) {
      const d = window.devicePixelRatio || 1;
      base = document.createElement('canvas');
      base.width = Math.round(w * d); base.height = Math.round(h * d);
      const b = base.getContext('2d');
      b.scale(d, d);
      RP.steps.forEach((s, k) => {
        if (k % 2 === 0) return;
        b.fillStyle = '#f3f6fa';
        b.fillRect(xOf(s.start, w), M.t, xOf(s.end, w) - xOf(s.start, w), h - M.t - M.b);
      });
      b.font = '10px system-ui, sans-serif';
      b.fillStyle = '#66748a';
      b.lineWidth = 1;
      const ys = niceTicks(lo, hi, 4);
      b.textAlign = 'right'; b.textBaseline = 'middle';
      for (const v of ys.ticks) {
        const y = Math.round(yOf(v, h)) + 0.5;
        b.strokeStyle = v === 0 ? '#c3ccd9' : '#edf0f5';
        segment(b, M.l, y, w - M.r, y);
        b.fillText(v.toFixed(ys.digits), M.l - 5, y);
      }
      const xs = niceTicks(T0, T1, Math.max(2, Math.floor((w - M.l) / 80)));
      b.textAlign = 'center'; b.textBaseline = 'top';
      for (const t of xs.ticks) b.fillText(t.toFixed(xs.digits) + ' s', xOf(t, w), h - M.b + 4);
      b.setLineDash([4, 3]);
      b.strokeStyle = 'rgba(220,38,38,0.6)';
      for (const v of opts.limits || []) {
        if (v <= lo || v >= hi) continue;
        const y = yOf(v, h);
        segment(b, M.l, y, w - M.r, y);
      }
      b.setLineDash([]);
      b.lineWidth = 1.3; b.lineJoin = 'round';
      for (const l of lines) {
        b.strokeStyle = l.color;
        b.beginPath();
        for (let i = 0; i < N; i++) {
          const x = xOf(T[i], w);
          const y = yOf(l.values[i], h);
          if (i) b.lineTo(x, y); else b.moveTo(x, y);
        }
        b.stroke();
      }
      b.strokeStyle = '#d5dbe5';
      b.strokeRect(M.l + 0.5, M.t + 0.5, w - M.l - M.r - 1, h - M.t - M.b - 1);
    }
    function draw() {
      const [w, h] = fitCanvas(cv, g);
      if (!base || size !== w + 'x' + h) { renderBase(w, h); size = w + 'x' + h; }
      g.clearRect(0, 0, w, h);
      g.drawImage(base, 0, 0, w, h);
      const x = xOf(state.t, w);
      g.strokeStyle = '#ef4444'; g.lineWidth = 1.5;
      segment(g, x, M.t, x, h - M.b);
      const [i, f] = locate(state.t);
      for (const l of lines) {
        g.beginPath(); g.arc(x, yOf(seriesAt(l.values, i, f), h), 2.6, 0, 2 * Math.PI);
        g.fillStyle = l.color; g.fill();
      }
    }
    function pick(e) {
      const r = cv.getBoundingClientRect();
      seek(T0 + (e.clientX - r.left - M.l) / (r.width - M.l - M.r) * DUR);
    }
    cv.addEventListener('pointerdown', (e) => { capture(cv, e); pick(e); });
    cv.addEventListener('pointermove', (e) => { if (e.buttons) pick(e); });
    plots.push({ draw });
  }
  function legend(parent, items) {
    parent.append(el('div', { class: 'legend' }, ...items.map(([label, color]) =>
      el('span', {}, el('span', { class: 'dot', style: 'background:' + color }), label))));
  }
  function buildPlots() {
    const box = $('plots');
    for (const arm of RP.arms) {
      const idx = RP.arm_joints[arm];
      const card = el('div', {});
      box.append(card);
      const colors = idx.map((_, k) => JOINT_COLORS[k % JOINT_COLORS.length]);
      const names = idx.map((j) => shortJoint(RP.joint_names[j], arm));
      const q = idx.map((j, k) => ({ values: RP.q[j], color: colors[k] }));
      const qd = idx.map((j, k) => ({ values: RP.qd[j], color: colors[k] }));
      const vmax = Math.max(...idx.map((j) => RP.limits.velocity[j]));
      let peak = 0;
      idx.forEach((j) => {
        const lim = RP.limits.velocity[j];
        for (const v of RP.qd[j]) if (lim > 0) peak = Math.max(peak, Math.abs(v) / lim);
      });
      makePlot(card, arm + ': joint positions (rad)', '', q, {});
      makePlot(card, arm + ': joint velocities (rad/s)',
        'peak ' + fmt(100 * peak, 0) + ' % of limit', qd,
        { symmetric: true, minSpan: 0.1, limits: [vmax, -vmax] });
      legend(card, names.map((n, k) => [n, colors[k]]));
    }
    if (RP.arm_distance) {
      const card = el('div', {});
      box.append(card);
      const tot = RE.totals || {};
      const info = isNum(tot.min_arm_distance_m)
        ? 'min ' + fmt(1000 * tot.min_arm_distance_m, 1, 'mm') + ' (' +
          pairText(tot.closest_pair) + ')'
        : '';
      makePlot(card, 'Distance between the arms (mm)', info,
        [{ values: RP.arm_distance.map((d) => 1000 * d), color: '#475569' }],
        { include: [0], limits: [0] });
    }
  }

  // ---------------------------------------------------------------- panels
  const nowCells = {};
  function kv(parent, key, id) {
    const dd = el('dd', { id });
    parent.append(el('dt', {}, key), dd);
    return dd;
  }
  function buildNow() {
    const now = $('now');
    const top = el('div', { class: 'now' }, el('h2', {}, 'Now'));
    const dl = el('dl', { class: 'kv' });
    top.append(dl);
    nowCells.time = kv(dl, 'time');
    nowCells.step = kv(dl, 'step');
    nowCells.segment = kv(dl, 'segment');
    nowCells.strategy = kv(dl, 'strategy');
    if (RP.arm_distance) nowCells.distance = kv(dl, 'arm distance');
    for (const arm of RP.arms) nowCells['grip_' + arm] = kv(dl, arm + ' gripper');
    now.append(top);
    nowCells.joints = {};
    for (const arm of RP.arms) {
      const sec = el('div', { class: 'now' },
        el('h2', {}, el('span', { class: 'dot', style: 'background:' + armColor[arm] }),
          arm + ' joints'));
      const table = el('table', { class: 'joints' },
        el('tr', {}, el('th', {}, 'joint'), el('th', { class: 'num' }, 'rad'),
          el('th', { class: 'num' }, 'deg'), el('th', { class: 'num' }, 'rad/s')));
      for (const j of RP.arm_joints[arm]) {
        const cells = [el('td', { class: 'num' }), el('td', { class: 'num' }),
          el('td', { class: 'num' })];
        table.append(el('tr', {}, el('td', {}, shortJoint(RP.joint_names[j], arm)), ...cells));
        nowCells.joints[j] = cells;
      }
      sec.append(table);
      now.append(sec);
    }
  }
  function updateNow() {
    const t = state.t;
    const [i, f] = locate(t);
    const step = lastStarted(RP.steps, t);
    const seg = lastStarted(RP.segments, t);
    const segReport = seg ? RE.segments[seg.index] || {} : {};
    nowCells.time.textContent = fmt(t, 3, 's') + ' / ' + fmt(T1, 3, 's');
    nowCells.step.textContent = step ? '#' + step.step + ' ' + step.label : DASH;
    nowCells.segment.textContent = seg ? seg.label : DASH;
    nowCells.strategy.textContent = seg
      ? seg.strategy + (segReport.merge ? ' \u00b7 merge ' + valueText(segReport.merge) : '')
      : DASH;
    if (nowCells.distance) {
      nowCells.distance.textContent = fmt(1000 * seriesAt(RP.arm_distance, i, f), 1, 'mm');
    }
    const grips = grippersAt(t);
    for (const arm of RP.arms) {
      const g = grips[arm];
      nowCells['grip_' + arm].textContent = g
        ? g.mode + (g.holds ? ' \u00b7 holds ' + g.holds : '') : DASH;
    }
    for (const [j, cells] of Object.entries(nowCells.joints)) {
      const q = seriesAt(RP.q[j], i, f);
      cells[0].textContent = q.toFixed(3);
      cells[1].textContent = (q * 180 / Math.PI).toFixed(1);
      cells[2].textContent = seriesAt(RP.qd[j], i, f).toFixed(3);
    }
    const hud = $('hud-step');
    hud.replaceChildren(el('div', { class: 'lbl' }, step ? '#' + step.step + ' ' + step.label
      : 'no step'), el('div', { class: 'muted' }, seg ? seg.label + ' \u00b7 ' + seg.strategy
      : ''));
  }

  const tl = { steps: [], segments: [], cursor: null };
  function pct(t) { return ((t - T0) / DUR * 100) + '%'; }
  function buildTimeline() {
    const box = $('timeline');
    const lane = (cls, name) => {
      box.append(el('div', { class: 'lane-name' }, name));
      const l = el('div', { class: 'lane ' + cls });
      l.addEventListener('click', (e) => {
        const r = l.getBoundingClientRect();
        seek(T0 + (e.clientX - r.left) / r.width * DUR);
      });
      box.append(l);
      return l;
    };
    const bar = (laneEl, item, color, text, title, store) => {
      const b = el('div', { class: 'bar', title, style: 'left:' + pct(item.start) + ';width:' +
        Math.max(0.15, (item.end - item.start) / DUR * 100) + '%;background:' + color }, text);
      b.addEventListener('click', (e) => {
        e.stopPropagation();
        setPlaying(false);
        seek(item.start);
      });
      laneEl.append(b);
      store.push([item, b]);
    };
    const steps = lane('', 'Steps');
    RP.steps.forEach((s, k) => bar(steps, s, STEP_COLORS[k % STEP_COLORS.length],
      '#' + s.step + ' ' + s.label, '#' + s.step + ' ' + s.label + ': ' + fmt(s.start, 2) +
      ' to ' + fmt(s.end, 2) + ' s', tl.steps));
    if (RE.mission && RE.mission.length) {
      // one lane per robot: which steps it works on, when, and what was inserted
      const arms = [...new Set(RE.mission.flatMap((m) => m.arms))];
      for (const arm of arms) {
        const ml = lane('', 'Mission: ' + arm);
        ml.dataset.mission = arm;
        for (const m of RE.mission.filter((x) => x.arms.includes(arm))) {
          const what = m.inserted ? m.step + ' (' + m.inserted + ')' : m.step;
          bar(ml, m, MISSION_COLORS[m.inserted || 'task'], what, what + ' [' +
            m.arms.join(' + ') + ']: ' + fmt(m.start, 2) + ' to ' + fmt(m.end, 2) + ' s', []);
        }
      }
    }
    const segs = lane('thin', 'Segments');
    const key = segs.previousSibling;
    for (const [name, color] of Object.entries(STRATEGY_COLORS)) {
      key.append(el('span', { style: 'margin-left:12px' },
        el('span', { class: 'dot', style: 'background:' + color }), name));
    }
    RP.segments.forEach((s) => bar(segs, s, STRATEGY_COLORS[s.strategy] || '#64748b', s.label,
      s.label + ' [' + s.strategy + ']: ' + fmt(s.end - s.start, 2) + ' s', tl.segments));
    if (RP.events.length) {
      const ev = lane('events', 'Gripper events');
      for (const e of RP.events) {
        ev.append(el('div', { class: 'tick', style: 'left:' + pct(e.time) + ';border-top-color:' +
          (armColor[e.arm] || '#333'), title: fmt(e.time, 3) + ' s: ' + e.arm + ' ' + e.mode +
          (e.holds ? ' (holds ' + e.holds + ')' : '') }));
      }
    }
    const axis = el('div', { class: 'axis' });
    const xs = niceTicks(T0, T1, 10);
    for (const t of xs.ticks) {
      axis.append(el('span', { style: 'left:' + pct(t) }, t.toFixed(xs.digits) + ' s'));
    }
    box.append(axis);
    tl.cursor = el('div', { id: 'tl-cursor' });
    box.append(tl.cursor);
  }
  function updateTimeline() {
    tl.cursor.style.left = pct(state.t);
    const step = lastStarted(RP.steps, state.t);
    const seg = lastStarted(RP.segments, state.t);
    for (const [s, b] of tl.steps) b.classList.toggle('active', s === step);
    for (const [s, b] of tl.segments) b.classList.toggle('active', s === seg);
  }

  const rows = [];
  function checksCell(v) {
    if (v === true) return el('td', { class: 'pass' }, '\u2713');
    if (v === false) return el('td', { class: 'fail' }, '\u2717');
    return el('td', { class: 'muted' }, DASH);
  }
  function fractions(fr) {
    const parts = Object.entries(fr || {}).map(([arm, v]) =>
      arm + ' ' + (isNum(v) ? fmt(100 * v, 0) + '%' : DASH));
    return parts.length ? parts.join(' \u00b7 ') : DASH;
  }
  function buildTable() {
    const table = $('steps');
    const heads = ['Step / segment', 'Strategy', 'Merge', 'Start (s)', 'Duration (s)',
      'Cartesian', 'Planning (s)', 'Min. distance (mm)', 'Closest pair', 'Checks'];
    const num = new Set([3, 4, 6, 7]);
    table.append(el('tr', {},
      ...heads.map((h, k) => el('th', num.has(k) ? { class: 'num' } : {}, h))));
    const td = (v, cls) => el('td', cls ? { class: cls } : {}, v);
    const mm = (d) => (isNum(d) ? fmt(1000 * d, 1) : DASH);
    for (const st of RE.steps) {
      const row = el('tr', { class: 'step-row clickable' }, td('#' + st.step + ' ' + st.label),
        td((st.strategies || []).join(', ')), td(''), td(fmt(st.start_s, 2), 'num'),
        td(fmt(st.duration_s, 2), 'num'), td(''), td(fmt(st.planning_time_s, 3), 'num'),
        td(mm(st.min_arm_distance_m), 'num'), td(pairText(st.closest_pair)),
        checksCell(st.checks_passed));
      row.addEventListener('click', () => seek(st.start_s));
      table.append(row);
      rows.push([st, row, 'step']);
      for (const k of st.segments) {
        const sg = RE.segments[k];
        const r = el('tr', { class: 'clickable' }, td(sg.label, 'indent'), td(sg.strategy),
          td(valueText(sg.merge)), td(fmt(sg.start_s, 2), 'num'), td(fmt(sg.duration_s, 2), 'num'),
          td(fractions(sg.cartesian_fraction), 'nowrap'), td(fmt(sg.planning_time_s, 3), 'num'),
          td(mm(sg.min_arm_distance_m), 'num'), td(pairText(sg.closest_pair)),
          checksCell(sg.checks_passed));
        r.addEventListener('click', () => seek(sg.start_s));
        table.append(r);
        rows.push([sg, r, 'segment']);
      }
    }
  }
  function updateTable() {
    const step = lastStarted(RP.steps, state.t);
    const seg = lastStarted(RP.segments, state.t);
    for (const [item, row, kind] of rows) {
      const on = kind === 'step' ? step && item.step === step.step
        : seg && item.index === seg.index;
      row.classList.toggle('active', Boolean(on));
    }
  }
  function buildHeader() {
    $('title').textContent = DATA.title;
    const tot = RE.totals || {};
    $('subtitle').textContent = [RE.plan, RE.execution, RE.driver].filter((x) => typeof x ===
      'string').join(' \u00b7 ');
    const chips = $('chips');
    const chip = (label, value, cls) => chips.append(el('span', { class: 'chip ' + (cls || '') },
      label + ' ', el('b', {}, value)));
    chip('cycle time', fmt(tot.cycle_time_s, 2, 's'));
    chip('steps', String(tot.steps));
    chip('segments', String(tot.segments));
    if (isNum(tot.planning_time_s)) chip('planning', fmt(tot.planning_time_s, 2, 's'));
    if (isNum(tot.min_arm_distance_m)) {
      chip('min. arm distance', fmt(1000 * tot.min_arm_distance_m, 1, 'mm'));
    }
    if (tot.checks_passed === true) chip('checks', 'passed', 'ok');
    else if (tot.checks_passed === false) chip('checks', 'FAILED', 'bad');
  }
  function buildDetails() {
    const own = new Set(['format', 'joint_names', 'arms', 'totals', 'steps', 'segments',
      'events']);
    const dl = $('details');
    let shown = 0;
    for (const [k, v] of Object.entries(RE)) {
      if (own.has(k)) continue;
      const text = typeof v === 'object' && v !== null ? JSON.stringify(v, null, 1) : valueText(v);
      dl.append(el('dt', {}, k), el('dd', {}, text.length > 60 ? el('pre', { class: 'json' },
        text.slice(0, 4000)) : text));
      shown += 1;
    }
    $('details-panel').hidden = shown === 0;
  }
  function buildLegend() {
    const box = $('hud-legend');
    for (const arm of RP.arms) {
      box.append(el('span', {}, el('span', { class: 'dot', style: 'background:' + armColor[arm] }),
        arm));
    }
    if (RP.cables.length) {
      box.append(el('span', {}, el('span', { class: 'dot', style: 'background:#1f2937' }),
        'cable'));
    }
  }

  // ---------------------------------------------------------------- interaction
  const slider = $('slider');
  const clock = $('clock');
  const playBtn = $('play');
  function render() {
    const drawn = drawView();
    updateNow();
    for (const p of plots) p.draw();
    updateTimeline();
    updateTable();
    updateClock();
    return drawn;
  }
  function updateClock() {
    slider.value = String(state.t);
    clock.textContent = fmt(state.t - T0, 2) + ' / ' + fmt(T1 - T0, 2) + ' s';
  }
  let pending = false;
  function invalidate() {
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; render(); });
  }
  function seek(t) {
    state.t = clampT(t);
    updateClock(); // at once; the drawing waits for the next frame
    invalidate();
  }
  function tick(now) {
    if (!state.playing) return;
    if (state.last !== null) {
      state.t += (now - state.last) / 1000 * state.speed;
      if (state.t >= T1) { state.t = T1; setPlaying(false); }
    }
    state.last = now;
    render();
    if (state.playing) requestAnimationFrame(tick);
  }
  function setPlaying(on) {
    state.playing = on;
    state.last = null;
    playBtn.textContent = on ? '\u275a\u275a Pause' : '\u25b6 Play';
    if (on) {
      if (state.t >= T1 - 1e-9) state.t = T0;
      requestAnimationFrame(tick);
    }
  }
  function toggle(btn, key) {
    btn.classList.toggle('on', state[key]);
    btn.addEventListener('click', () => {
      state[key] = !state[key];
      btn.classList.toggle('on', state[key]);
      invalidate();
    });
  }
  function bindControls() {
    slider.min = String(T0);
    slider.max = String(T1);
    slider.step = 'any';
    slider.addEventListener('input', () => { setPlaying(false); seek(Number(slider.value)); });
    playBtn.addEventListener('click', () => setPlaying(!state.playing));
    $('speed').addEventListener('change', (e) => { state.speed = Number(e.target.value); });
    toggle($('btn-trails'), 'trails');
    toggle($('btn-keys'), 'keys');
    toggle($('btn-wire'), 'wire');
    $('btn-reset').addEventListener('click', () => { resetCamera(); invalidate(); });
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY, pan: e.button !== 0 || e.shiftKey };
      capture(canvas, e);
      canvas.classList.add('dragging');
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x;
      const dy = e.clientY - drag.y;
      drag.x = e.clientX; drag.y = e.clientY;
      if (drag.pan) {
        const V = makeView(canvas.clientWidth, canvas.clientHeight);
        const s = cam.dist / V.focal;
        for (let k = 0; k < 3; k++) cam.target[k] += (-dx * V.r[k] + dy * V.u[k]) * s;
      } else {
        cam.az -= dx * 0.008;
        cam.el = Math.max(-1.45, Math.min(1.45, cam.el + dy * 0.008));
      }
      invalidate();
    });
    const end = () => { drag = null; canvas.classList.remove('dragging'); };
    canvas.addEventListener('pointerup', end);
    canvas.addEventListener('pointercancel', end);
    canvas.addEventListener('contextmenu', (e) => e.preventDefault());
    canvas.addEventListener('dblclick', () => { resetCamera(); invalidate(); });
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      cam.dist = Math.max(0.05, Math.min(50, cam.dist * Math.exp(e.deltaY * 0.0012)));
      invalidate();
    }, { passive: false });
    document.addEventListener('keydown', (e) => {
      if (e.target instanceof HTMLSelectElement) return;
      const dt = e.shiftKey ? 1 : (N > 1 ? (T[N - 1] - T[0]) / (N - 1) : 0.04);
      if (e.key === ' ') { e.preventDefault(); setPlaying(!state.playing); }
      else if (e.key === 'ArrowRight') { e.preventDefault(); seek(state.t + dt); }
      else if (e.key === 'ArrowLeft') { e.preventDefault(); seek(state.t - dt); }
      else if (e.key === 'Home') seek(T0);
      else if (e.key === 'End') seek(T1);
    });
    window.addEventListener('resize', invalidate);
  }

  function init() {
    buildHeader();
    buildNow();
    buildTimeline();
    buildPlots();
    buildTable();
    buildDetails();
    buildLegend();
    bindControls();
    resetCamera();
    const hash = (key) => {
      const m = new RegExp('(?:^#|&)' + key + '=([0-9.eE+-]+)').exec(location.hash);
      return m ? Number(m[1]) : null;
    };
    if (hash('t') !== null) state.t = clampT(hash('t') + T0);
    if (hash('az') !== null) cam.az = hash('az');
    if (hash('el') !== null) cam.el = Math.max(-1.45, Math.min(1.45, hash('el')));
    const drawn = render();
    const r = canvas.getBoundingClientRect();
    document.body.dataset.canvas = [r.left + window.scrollX, r.top + window.scrollY, r.width,
      r.height].map(Math.round).join(',');
    document.body.dataset.drawn = String(drawn.shapes);
    document.body.dataset.cables = String(drawn.cables);
    if (document.body.dataset.status !== 'error') document.body.dataset.status = 'ok';
  }
  try {
    init();
  } catch (e) {
    window.ceFail('init: ' + ((e && e.stack) || e));
  }
})();
