// report.html's script (see base.js): a plan that failed to compile; the failures panel, and
// the 3D view at the pose where the compile stopped, the colliding pair highlighted and named.
/* global $, cam, ctx, DASH, el, fmt, invalidate, jointUnit, NEAR, nowCells, pairText, project, RE,
   RP, state */
/* exported buildFailure, FAIL_COLOR, failureColor, failurePose, focusFailure, markFailure,
   showFailure, updateFailureHud */

const FAILED = RE.failure || null;
const POSES = (RP.failure && RP.failure.poses) || [];
const FAIL_COLOR = [225, 29, 72];
state.fail = -1; // the pose shown (an index into POSES), or -1: the replay at state.t

function failurePose() { return state.fail >= 0 ? POSES[state.fail] : null; }
function showFailure(k) {
  state.fail = k;
  const btn = $('btn-fail');
  if (btn) btn.classList.toggle('on', k >= 0);
  document.querySelectorAll('#failure-panel li').forEach((li) => {
    li.classList.toggle('active', Number(li.dataset.pose) === k && k >= 0);
  });
}
// the highlight colour of a static mesh named by the pose's pair, else null
function failureColor(name) {
  const pose = failurePose();
  return pose && pose.statics.includes(name) ? FAIL_COLOR : null;
}
function poseWords(pose) {
  if (!pose.pair) return 'the arms where it stopped';
  const what = { collision: 'colliding', clearance: 'too close', transit: 'in the way' };
  return (what[pose.kind] || 'named') + ': ' + pairText(pose.pair);
}
function buildFailure() {
  const panel = $('failure-panel');
  if (!FAILED) return;
  panel.hidden = false;
  const n = FAILED.failures.length;
  panel.append(el('h2', {}, 'Plan failed: ' + n + (n === 1 ? ' failure' : ' failures') +
    '; ' + FAILED.compiled_segments + ' segments compiled before it'));
  const list = el('ol', {});
  FAILED.failures.forEach((f, k) => {
    const pose = POSES.findIndex((p) => p.failure === k);
    const where = f.segment ? 'segment ' + f.segment : 'step ' + (f.step_label || DASH);
    const li = el('li', { 'data-pose': String(pose) }, el('div', { class: 'where' }, where +
      (f.kind ? ' \u00b7 ' + f.kind : '') + (f.time_s !== null && f.time_s !== undefined
      ? ' \u00b7 t = ' + fmt(f.time_s, 3, 's') : '')),
    ...f.messages.map((m) => el('pre', { class: 'msg' }, m)));
    if (pose >= 0) {
      li.append(el('div', { class: 'pair' }, poseWords(POSES[pose])));
      li.classList.add('clickable');
      li.addEventListener('click', () => { showFailure(pose); invalidate(); });
    }
    list.append(li);
  });
  panel.append(list);
  const btn = $('btn-fail');
  btn.hidden = POSES.length === 0;
  btn.addEventListener('click', () => {
    showFailure(state.fail >= 0 ? -1 : 0);
    invalidate();
  });
  showFailure(POSES.length ? 0 : -1);
}
// over the drawing: the targets not reached (crosses) and the pair's names by its shapes; the
// number of highlighted shapes
function markFailure(V, pose) {
  const red = 'rgb(' + FAIL_COLOR.join(',') + ')';
  ctx.lineWidth = 2.5;
  ctx.strokeStyle = red;
  for (const p of Object.values(pose.targets)) {
    const q = project(V, p[0], p[1], p[2]);
    if (q[2] < NEAR) continue;
    ctx.beginPath();
    ctx.moveTo(q[0] - 7, q[1] - 7); ctx.lineTo(q[0] + 7, q[1] + 7);
    ctx.moveTo(q[0] + 7, q[1] - 7); ctx.lineTo(q[0] - 7, q[1] + 7);
    ctx.stroke();
  }
  const named = namedShapes(pose);
  ctx.font = '600 12px system-ui, sans-serif';
  ctx.fillStyle = red;
  for (const [name, p] of named) {
    const q = project(V, p[0], p[1], p[2]);
    if (q[2] >= NEAR) ctx.fillText(name, q[0] + 8, q[1] - 8);
  }
  return named.length;
}
// the pose's highlighted shapes: [name, a point of it (a link's first, a mesh's centroid)]
function namedShapes(pose) {
  const named = pose.links.filter((l) => l.highlight).map((l) => [l.name, l.points]);
  for (const s of RP.static.filter((m) => pose.statics.includes(m.name))) {
    const v = s.vertices;
    const c = [0, 0, 0];
    for (let k = 0; k < v.length; k++) c[k % 3] += 3 * v[k] / v.length;
    named.push([s.name, c]);
  }
  return named;
}
// the camera closer, on the pair (after resetCamera: a double-click goes back to the cell)
function focusFailure() {
  const pose = failurePose();
  const named = pose ? namedShapes(pose) : [];
  if (!named.length) return;
  cam.target = [0, 1, 2].map((k) => named.reduce((sum, [, p]) => sum + p[k], 0) / named.length);
  cam.dist = Math.max(0.6, 0.6 * cam.dist);
}
// the HUD and the 'now' panel at the pose shown (its joints, no velocities)
function updateFailureHud() {
  const pose = failurePose();
  if (!pose) return;
  const f = FAILED.failures[pose.failure];
  $('hud-step').replaceChildren(el('div', { class: 'lbl fail-text' }, 'FAILED: ' +
    (f.segment || f.step_label || '')), el('div', {}, poseWords(pose)));
  nowCells.segment.textContent = f.segment || DASH;
  for (const [j, cells] of Object.entries(nowCells.joints)) {
    const u = jointUnit(j); // mm for a prismatic joint, deg for a revolute one
    cells[0].textContent = fmt(u.k * f.q[j], 1, u.pos);
    cells[1].textContent = DASH; // a pose: no velocity
  }
}
