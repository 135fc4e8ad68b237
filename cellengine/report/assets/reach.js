// report.html's script (see base.js): the cell page (`cellengine show CELL --html`, RP.reach:
// each keypoint's arms that reach it). Every keypoint is drawn over the scene, coloured by the
// arms that reach it and labelled; a table lists them; the run's panels and playback go.
/* global $, armColor, ctx, el, fmt, NEAR, project, RP */
/* exported drawReach */

const REACH_ALL = '#16a34a';
const REACH_NONE = '#dc2626';
const REACH_SOME = '#a16207'; // several arms, not all (cells of three or more)
const reachOf = RP.reach || {};
function reachClass(arms) {
  if (!arms.length) return 'none';
  if (arms.length === RP.arms.length) return 'all';
  return arms.length === 1 ? arms[0] : 'some';
}
function reachColor(arms) {
  const k = reachClass(arms);
  if (k === 'all') return REACH_ALL;
  if (k === 'none') return REACH_NONE;
  return k === 'some' ? REACH_SOME : armColor[k];
}
function reachText(arms) {
  const k = reachClass(arms);
  if (k === 'none') return 'no arm';
  if (k === 'all') return 'every arm';
  return k === 'some' ? arms.join(', ') : k + ' only';
}
// drawn over everything, as the cables are: the keypoints are what the page is about
function drawReach(V) {
  const counts = {};
  let labelled = 0;
  ctx.font = '600 11px system-ui, sans-serif';
  ctx.lineJoin = 'round';
  for (const kp of RP.keypoints) {
    const arms = reachOf[kp.name] || [];
    const q = project(V, kp.p[0], kp.p[1], kp.p[2]);
    if (q[2] < NEAR) continue;
    const k = reachClass(arms);
    counts[k] = (counts[k] || 0) + 1;
    ctx.beginPath(); ctx.arc(q[0], q[1], 5, 0, 2 * Math.PI);
    ctx.fillStyle = reachColor(arms); ctx.fill();
    ctx.strokeStyle = '#111827'; ctx.lineWidth = 1.2; ctx.stroke();
    ctx.strokeStyle = 'rgba(255,255,255,0.85)'; ctx.lineWidth = 3;
    ctx.strokeText(kp.name, q[0] + 8, q[1] + 4);
    ctx.fillStyle = '#1f2933';
    ctx.fillText(kp.name, q[0] + 8, q[1] + 4);
    labelled += 1;
  }
  // what the browser tests read: keypoints drawn with a label, and how many of each colour
  document.body.dataset.labelled = String(labelled);
  document.body.dataset.reach = Object.keys(counts).sort().map((k) => k + ':' + counts[k])
    .join(',');
}
function buildReach() {
  for (const id of ['timeline', 'plots', 'steps']) $(id).closest('section').hidden = true;
  for (const id of ['chips', 'play', 'slider', 'clock', 'speed', 'btn-trails', 'now',
    'hud-step']) {
    $(id).hidden = true;
  }
  $('now').closest('.row1').style.gridTemplateColumns = 'minmax(0, 1fr)';
  const legend = el('div', { class: 'hud', id: 'hud-reach', style: 'left:10px;top:10px' },
    el('b', {}, 'Keypoints reached by'));
  const kinds = [[REACH_ALL, 'every arm'], ...RP.arms.map((a) => [armColor[a], a + ' only']),
    [REACH_NONE, 'no arm']];
  if (RP.arms.length > 2) kinds.splice(-1, 0, [REACH_SOME, 'some arms']);
  for (const [color, text] of kinds) {
    legend.append(el('div', {}, el('span', { class: 'dot', style: 'background:' + color }),
      text));
  }
  $('view-wrap').append(legend);
  const table = el('table', { id: 'reach' }, el('tr', {}, el('th', {}, 'Keypoint'),
    el('th', { class: 'num' }, 'x, y, z (mm)'), el('th', {}, 'Reached by')));
  for (const kp of RP.keypoints) {
    const arms = reachOf[kp.name] || [];
    const xyz = kp.p.map((v) => fmt(1000 * v, 1)).join(', ');
    table.append(el('tr', {}, el('td', {}, kp.name), el('td', { class: 'num' }, xyz),
      el('td', {}, el('span', { class: 'dot', style: 'background:' + reachColor(arms) }),
        reachText(arms))));
  }
  const note = 'The tool at each keypoint: its z down the keypoint\u2019s z, its x along the ' +
    'keypoint\u2019s x (or turned half a turn about its z); an arm reaches the keypoint when ' +
    'its IK has a solution within the joint limits. Collisions are not checked.';
  $('view-wrap').closest('.wrap').append(el('section', { class: 'panel' },
    el('h2', {}, 'Keypoints and the arms that reach them'), el('p', { class: 'muted' }, note),
    table));
}
if (RP.reach) buildReach();
