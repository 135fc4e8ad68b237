// report.html's script (see base.js): the clock; the replay's samples at a time, the current
// step, segment and grippers.
/* global RP */
/* exported clampT, DUR, grippersAt, toolsAt, lastStarted, linkAt, locate, seriesAt, state, tcpAt */

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
// the tool each arm carries at time t (null: a bare flange)
function toolsAt(t) {
  const out = Object.assign({}, RP.tools.start);
  for (const c of RP.tools.changes) if (c.time <= t + 1e-9) out[c.arm] = c.tool;
  return out;
}
function grippersAt(t) {
  const g = {};
  for (const a of RP.arms) g[a] = null;
  for (const e of RP.events) if (e.time <= t + 1e-9) g[e.arm] = e;
  return g;
}
