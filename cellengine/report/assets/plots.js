// report.html's script (see base.js): the joint plots (positions; velocities against their
// limits; the distance between the arms).
/* global $, capture, closestMarks, drawMarks, DUR, el, fitCanvas, fmt, isNum, JOINT_COLORS,
   jointKind, JOINT_UNITS, locate, N, pairText, RE, RP, seek, segment, seriesAt, shortJoint, state,
   T, T0, T1 */
/* exported buildPlots */

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
    drawMarks(b, opts.marks, (t) => xOf(t, w), M.t, h - M.b);
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
// per arm and joint type (lengths and angles apart), in the type's units
function buildPlots() {
  const box = $('plots');
  for (const arm of RP.arms) {
    const all = RP.arm_joints[arm];
    const card = el('div', {});
    box.append(card);
    const colors = all.map((_, k) => JOINT_COLORS[k % JOINT_COLORS.length]);
    const kinds = [...new Set(all.map(jointKind))];
    for (const kind of kinds) {
      const u = JOINT_UNITS[kind];
      const idx = all.filter((j) => jointKind(j) === kind);
      const color = (j) => colors[all.indexOf(j)];
      const q = idx.map((j) => ({ values: RP.q[j].map((v) => v * u.k), color: color(j) }));
      const qd = idx.map((j) => ({ values: RP.qd[j].map((v) => v * u.k), color: color(j) }));
      const vmax = Math.max(...idx.map((j) => RP.limits.velocity[j])) * u.k;
      let peak = 0;
      idx.forEach((j) => {
        const lim = RP.limits.velocity[j];
        for (const v of RP.qd[j]) if (lim > 0) peak = Math.max(peak, Math.abs(v) / lim);
      });
      const what = arm + ': ' + (kinds.length > 1 ? kind + ' joint ' : 'joint ');
      makePlot(card, what + 'positions (' + u.pos + ')', '', q, { marks: closestMarks() });
      makePlot(card, what + 'velocities (' + u.vel + ')',
        'peak ' + fmt(100 * peak, 0) + ' % of limit', qd,
        { symmetric: true, minSpan: 0.1 * u.k, limits: [vmax, -vmax], marks: closestMarks() });
    }
    legend(card, all.map((j, k) => [shortJoint(RP.joint_names[j], arm), colors[k]]));
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
      { include: [0], limits: [0], marks: closestMarks() });
  }
}
