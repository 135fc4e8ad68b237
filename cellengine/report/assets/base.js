// report.html's script, first part: the embedded data (decoded), colours, constants and
// small helpers. page.py (SCRIPTS) joins the parts, in order, into one function, the page's
// scope: a part's /* global */ names are defined by other parts, its /* exported */ ones are
// used only by others (ESLint reports one missing). The header, up to the blank line, stays out
// of the page.
/* exported $, BG, capture, css, el, fmt, FOV, GROUP_COLORS, JOINT_COLORS, MISSION_COLORS, mix,
   NEAR, pairText, partName, RE, rgb, shortJoint, STEP_COLORS, STRATEGY_COLORS, valueText,
   WHITE */

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
RP.objects = RP.objects || [];
for (const o of RP.objects) o.points = unpack(o.points);

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
  } catch {
    // a synthetic or already released pointer: dragging works without capture
  }
}
// a collision object's name for people (replay.py's part_names; a tool in its changer slot,
// 'gun@slot(#k)', as in its slot; a cable laid on the board, 'TOP@laid(#k)', as laid; a held
// object, 'vial3@robot1', as held by its arm; else without its '#k')
function partName(n) {
  const parked = /^(.+)@(slot|laid)(#\d+)?$/.exec(n);
  if (parked) return parked[1] + (parked[2] === 'slot' ? ' (in its slot)' : ' (laid)');
  const held = /^(.+)@([^@]+)$/.exec(n);
  if (held) return held[1] + ' (held by ' + held[2] + ')';
  return (RP.part_names || {})[n] || String(n).replace(/#\d+$/, '');
}
function pairText(p) { return Array.isArray(p) ? p.map(partName).join(' \u2194 ') : DASH; }
function valueText(v) {
  if (v === null || v === undefined) return DASH;
  return typeof v === 'string' || typeof v === 'number' ? String(v) : JSON.stringify(v);
}
