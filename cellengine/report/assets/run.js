// report.html's script (see base.js): what the run did (report.json's run, written when the
// arms start and again when the run ends): a status chip first in the header, a 'Run' panel
// (outcome, segments finished, resumes, masses measured, runtime choices, the servo loop) and
// where a fault stopped the arms on the timeline. A plan alone (no run) shows none of these.
/* global $, DASH, el, fmt, isNum, pct, RE, RP */
/* exported buildRun, RUN_STATUS */

const RUN = RE.run || null;
const RUN_STATUS = {
  running: ['not finished', 'warn'], completed: ['completed', 'ok'], fault: ['FAULT', 'bad'],
  interrupted: ['INTERRUPTED', 'bad'], error: ['STOPPED', 'bad'],
};
function segText(k) {
  const s = RP.segments[k];
  return isNum(k) ? 'segment ' + (k + 1) + (s ? ' (' + s.name + ')' : '') : DASH;
}
function runHeadline() {
  const [word] = RUN_STATUS[RUN.outcome] || [RUN.outcome];
  const f = RUN.fault;
  if (RUN.outcome === 'fault' && f) {
    return word + ': ' + f.kind + (f.arm ? ', arm ' + f.arm : '') +
      (isNum(f.time) ? ', at ' + fmt(f.time, 2, 's') : '');
  }
  if (RUN.outcome === 'interrupted' && f && isNum(f.time)) {
    return word + ' at ' + fmt(f.time, 2, 's');
  }
  if (RUN.outcome === 'running') return word + ' (running, or killed)';
  return word;
}
function runRows() {
  const rows = [['outcome', runHeadline()]];
  if (RUN.message) rows.push(['message', RUN.message]);
  rows.push(['segments finished', RUN.segments_finished + ' of ' + RUN.segments]);
  if (RUN.stopped_in) rows.push(['stopped in', segText(RUN.stopped_in.segment)]);
  for (const r of RUN.resumed || []) rows.push(['resumed', 'from ' + segText(r.from_segment)]);
  if (RUN.replanned) rows.push(['replanned', RUN.replanned + ' time(s), after weighing']);
  for (const m of RUN.measured || []) {
    rows.push(['measured ' + m.object, fmt(1000 * m.mass_kg, 2, 'g') + ' (' + m.arm +
      (isNum(m.step) ? ', step ' + (m.step + 1) : '') + ')']);
  }
  for (const c of RUN.choices || []) {
    rows.push(['step ' + (c.step + 1) + ' ' + c.field, c.rule.replace('_of', ' of') + ' ' +
      c.of.join(', ') + ': ' + (c.chose || DASH) + ' (masses ' + c.by + ')']);
  }
  const s = RUN.servo;
  if (s && s.ticks) {
    const e = s.period_error_ms;
    rows.push(['servo loop', fmt(s.rate_hz, 1, 'Hz') + ' over ' + s.ticks + ' ticks (nominal ' +
      fmt(s.nominal_period_ms, 1, 'ms') + ')']);
    rows.push(['period error', 'p50 ' + fmt(e.p50, 3) + ' \u00b7 p99 ' + fmt(e.p99, 3) +
      ' \u00b7 p99.9 ' + fmt(e['p99.9'], 3) + ' \u00b7 max ' + fmt(e.max, 3) + ' ms']);
    if ((s.stop_commands_ms || []).length) {
      rows.push(['stop commands', s.stop_commands_ms.map((v) => fmt(v, 1)).join(', ') + ' ms']);
    }
  }
  rows.push(['driver', RUN.driver]);
  return rows;
}
function buildRun() {
  document.body.dataset.outcome = RUN ? RUN.outcome : 'plan';
  if (!RUN) return;
  const [, cls] = RUN_STATUS[RUN.outcome] || ['', 'bad'];
  $('chips').prepend(el('span', { class: 'chip ' + cls, id: 'run-status' }, 'run ',
    el('b', {}, runHeadline())));
  const dl = el('dl', { class: 'kv', id: 'run' });
  for (const [k, v] of runRows()) dl.append(el('dt', {}, k), el('dd', {}, v));
  const panel = el('section', { class: 'panel', id: 'run-panel' }, el('h2', {}, 'Run'), dl);
  document.querySelector('.row1').after(panel);
  const f = RUN.fault;
  if (f && isNum(f.time)) {
    $('timeline').append(el('div', { class: 'stop-mark', style: 'left:' + pct(f.time),
      title: runHeadline() }));
  }
}
