// report.html's script (see base.js): the panels; 'now' (time, step, grippers, joints), the
// step timeline, the steps table, the header's chips, the run's details, the 3D legend.
/* global $, armColor, DASH, DATA, DUR, el, fmt, grippersAt, toolsAt, isNum, jointUnit, lastStarted,
   locate, MISSION_COLORS, niceTicks, pairText, RE, RP, seek, seriesAt, setPlaying, shortJoint, state,
   STEP_COLORS, STRATEGY_COLORS, T0, T1, valueText */
/* exported buildDetails, buildHeader, buildLegend, buildNow, buildTable, buildTimeline, pct,
   updateNow, updateTable, updateTimeline */

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
  if (RP.tools.changes.length) {
    for (const arm of RP.arms) nowCells['tool_' + arm] = kv(dl, arm + ' tool');
  }
  now.append(top);
  nowCells.joints = {};
  for (const arm of RP.arms) {
    const sec = el('div', { class: 'now' },
      el('h2', {}, el('span', { class: 'dot', style: 'background:' + armColor[arm] }),
        arm + ' joints'));
    const table = el('table', { class: 'joints' },
      el('tr', {}, el('th', {}, 'joint'), el('th', { class: 'num' }, 'position'),
        el('th', { class: 'num' }, 'velocity')));
    for (const j of RP.arm_joints[arm]) {
      const cells = [el('td', { class: 'num' }), el('td', { class: 'num' })];
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
  nowCells.step.textContent = step ? stepTitle(step) : DASH;
  nowCells.segment.textContent = seg ? segName(seg) : DASH;
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
  if (RP.tools.changes.length) {
    const tools = toolsAt(t);
    for (const arm of RP.arms) nowCells['tool_' + arm].textContent = tools[arm] || 'none';
  }
  for (const [j, cells] of Object.entries(nowCells.joints)) {
    const u = jointUnit(j);
    cells[0].textContent = fmt(u.k * seriesAt(RP.q[j], i, f), 1, u.pos);
    cells[1].textContent = fmt(u.k * seriesAt(RP.qd[j], i, f), 1, u.vel);
  }
  const hud = $('hud-step');
  hud.replaceChildren(el('div', { class: 'lbl' }, step ? stepTitle(step) : 'no step'),
    el('div', { class: 'muted' }, seg ? segName(seg) + ' \u00b7 ' + seg.strategy : ''));
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
    stepTitle(s), stepTitle(s) + ': ' + fmt(s.start, 2) +
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
  if (RE.streams && RE.streams.at_once) {
    // both robots at once: each robot's segments where they ran, and every wait the
    // streams inserted before one (hatched, from when its order let it start)
    for (const [arm, items] of Object.entries(RE.streams.lanes)) {
      const sl = lane('thin', 'At once: ' + arm);
      sl.dataset.stream = arm;
      for (const s of items) {
        if (s.wait_s > 0) {
          const w = { start: s.start - s.wait_s, end: s.start };
          const why = 'waited ' + fmt(s.wait_s, 2) + ' s before ' + s.label + ': ' +
            (s.waited_for || 'its order');
          const b = el('div', { class: 'bar wait', title: why, style: 'left:' + pct(w.start) +
            ';width:' + Math.max(0.15, s.wait_s / DUR * 100) + '%' });
          sl.append(b);
        }
        const short = s.label.split(': ').slice(1).join(': ') || s.label;
        bar(sl, s, armColor[arm] || '#64748b', short, s.label + ': ' + fmt(s.start, 2) +
          ' to ' + fmt(s.end, 2) + ' s', []);
      }
    }
  }
  const segs = lane('thin', 'Segments');
  const key = segs.previousSibling;
  for (const [name, color] of Object.entries(STRATEGY_COLORS)) {
    key.append(el('span', { style: 'margin-left:12px' },
      el('span', { class: 'dot', style: 'background:' + color }), name));
  }
  RP.segments.forEach((s) => bar(segs, s, STRATEGY_COLORS[s.strategy] || '#64748b', segName(s),
    segName(s) + ' [' + s.strategy + ']: ' + fmt(s.end - s.start, 2) + ' s', tl.segments));
  if (RP.events.length) {
    const ev = lane('events', 'Gripper events');
    for (const e of RP.events) {
      ev.append(el('div', { class: 'tick', style: 'left:' + pct(e.time) + ';border-top-color:' +
        (armColor[e.arm] || '#333'), title: fmt(e.time, 3) + ' s: ' + e.arm + ' ' + e.mode +
        (e.holds ? ' (holds ' + e.holds + ')' : '') }));
    }
  }
  if (RP.tools.changes.length) {
    const ch = lane('events', 'Tool changes');
    for (const c of RP.tools.changes) {
      ch.append(el('div', { class: 'tick', style: 'left:' + pct(c.time) + ';border-top-color:' +
        (armColor[c.arm] || '#333'), title: fmt(c.time, 3) + ' s: ' + c.arm + ' ' +
        (c.tool ? 'takes ' + c.tool : 'leaves ' + c.was + ' in its slot') }));
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
// A segment's least clearance, arms and environment, in mm; red under the cell's clearance
function clearanceCell(c) {
  const limit = RE.clearance_m;
  const parts = [];
  let under = false;
  for (const [kind, short] of [['arms', 'arms'], ['environment', 'env']]) {
    const f = c && c[kind];
    if (!f || !isNum(f.distance_m)) continue;
    under = under || (isNum(limit) && f.distance_m < limit);
    parts.push(short + ' ' + fmt(1000 * f.distance_m, 1));
  }
  const title = ['arms', 'environment'].filter((k) => c && c[k])
    .map((k) => k + ': ' + pairText(c[k].pair)).join('; ');
  return el('td', { class: 'nowrap' + (under ? ' fail' : ''), title },
    parts.length ? parts.join(' \u00b7 ') : DASH);
}
function buildTable() {
  const table = $('steps');
  const heads = ['Step / segment', 'Strategy', 'Merge', 'Start (s)', 'Duration (s)',
    'Cartesian', 'Planning (s)', 'Min. distance (mm)', 'Closest pair', 'Clearance (mm)',
    'Checks'];
  const num = new Set([3, 4, 6, 7]);
  table.append(el('tr', {},
    ...heads.map((h, k) => el('th', num.has(k) ? { class: 'num' } : {}, h))));
  const td = (v, cls) => el('td', cls ? { class: cls } : {}, v);
  const mm = (d) => (isNum(d) ? fmt(1000 * d, 1) : DASH);
  for (const st of RE.steps) {
    const shown = RP.steps.find((x) => x.step === st.step) || st;
    const row = el('tr', { class: 'step-row clickable' }, td(stepTitle(shown)),
      td((st.strategies || []).join(', ')), td(''), td(fmt(st.start_s, 2), 'num'),
      td(fmt(st.duration_s, 2), 'num'), td(''), td(fmt(st.planning_time_s, 3), 'num'),
      td(mm(st.min_arm_distance_m), 'num'), td(pairText(st.closest_pair)), td(''),
      checksCell(st.checks_passed));
    row.addEventListener('click', () => seek(st.start_s));
    table.append(row);
    rows.push([st, row, 'step']);
    for (const k of st.segments) {
      const sg = RE.segments[k];
      const r = el('tr', { class: 'clickable' }, td(segName(RP.segments[k] || sg), 'indent'), td(sg.strategy),
        td(valueText(sg.merge)), td(fmt(sg.start_s, 2), 'num'), td(fmt(sg.duration_s, 2), 'num'),
        td(fractions(sg.cartesian_fraction), 'nowrap'), td(fmt(sg.planning_time_s, 3), 'num'),
        td(mm(sg.min_arm_distance_m), 'num'), td(pairText(sg.closest_pair)),
        clearanceCell(sg.clearance), checksCell(sg.checks_passed));
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
// under the cell's clearance: bad; within half of it again: a warning
function clearanceClass(d) {
  const limit = RE.clearance_m;
  if (!isNum(limit) || !isNum(d)) return '';
  return d < limit ? 'bad' : d < 1.5 * limit ? 'warn' : '';
}
// a step counted from 1, by its plan name, with the object a runtime choice of the run picked;
// a segment without its step's part (replay.py)
function stepTitle(s) {
  const title = s.title || 'step ' + (s.step + 1) + ' ' + s.label;
  const chosen = ((RE.run || {}).choices || []).find((c) => c.step === s.step && c.chose);
  return chosen ? title + ' \u2192 ' + chosen.chose : title;
}
function segName(s) { return s.name || s.label; }
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
  for (const [kind, label] of [['arms', 'arms'], ['environment', 'environment']]) {
    const c = (tot.clearance || {})[kind];
    if (!c || !isNum(c.distance_m)) continue;
    chip('min. clearance, ' + label, fmt(1000 * c.distance_m, 1, 'mm') + ' (' +
      pairText(c.pair) + ')', clearanceClass(c.distance_m));
    const pill = chips.lastChild;
    if (isNum(c.time_s)) {
      pill.classList.add('clickable');
      pill.title = 'at ' + fmt(c.time_s, 2, 's') + ': click to go there';
      pill.addEventListener('click', () => { setPlaying(false); seek(c.time_s); });
    }
  }
  if (isNum(RE.clearance_m)) chip("cell's clearance", fmt(1000 * RE.clearance_m, 0, 'mm'));
  const checks = RE.run ? 'plan checks' : 'checks'; // a run's own outcome is its status chip
  if (RE.failure) chip('plan', 'FAILED', 'bad');
  if (tot.checks_passed === true) chip(checks, 'passed', 'ok');
  else if (tot.checks_passed === false) chip(checks, 'FAILED', 'bad');
}
function buildDetails() {
  const own = new Set(['format', 'joint_names', 'arms', 'totals', 'steps', 'segments',
    'events', 'run', 'failure']);
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
