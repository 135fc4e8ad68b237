// report.html's script (see base.js): the keypoints' names beside their dots (with the
// 'keypoints' button), nearest first; a label that would cover one already drawn is left out,
// so many keypoints stay readable (zoom in to see the others).
/* global ctx, NEAR, project, RP */
/* exported drawKeyLabels */

// one platform: its name is left out of every label
const KEY_PREFIX = (function () {
  const heads = new Set(RP.keypoints.map((k) => k.name.split('.')[0]));
  return heads.size === 1 ? [...heads][0] + '.' : '';
})();
function drawKeyLabels(V) {
  ctx.font = '10px system-ui, sans-serif';
  ctx.textBaseline = 'middle';
  const items = [];
  for (const kp of RP.keypoints) {
    const q = project(V, kp.p[0], kp.p[1], kp.p[2]);
    const name = kp.name.startsWith(KEY_PREFIX) ? kp.name.slice(KEY_PREFIX.length) : kp.name;
    if (q[2] >= NEAR) items.push([q, name]);
  }
  items.sort((a, b) => a[0][2] - b[0][2]);
  const taken = [];
  let drawn = 0;
  for (const [q, text] of items) {
    const w = ctx.measureText(text).width + 4;
    const box = [q[0] + 4, q[1] - 7, q[0] + 4 + w, q[1] + 7];
    if (taken.some((b) => box[0] < b[2] && b[0] < box[2] && box[1] < b[3] && b[1] < box[3])) {
      continue;
    }
    taken.push(box);
    ctx.fillStyle = 'rgba(255,255,255,0.8)';
    ctx.fillRect(box[0], box[1], w, 14);
    ctx.fillStyle = '#1e293b';
    ctx.fillText(text, box[0] + 2, q[1]);
    drawn += 1;
  }
  ctx.textBaseline = 'alphabetic';
  return drawn;
}
