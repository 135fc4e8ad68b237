// report.html's script (see base.js): camera presets (from the top and from the front, the whole
// scene in view; fitted to the platforms) and the view's extra buttons (zones, the moment of least clearance), added
// to the controls beside the 'view' button.
/* global $, cam, closestMarks, el, FOV, RP, sceneBounds, seek, state */
/* exported addViewButtons, setView */

const TOP_EL = Math.PI / 2 - 1e-3; // straight down (the view needs a horizontal right vector)

// the platforms' elements and the lab objects (else every non-ground mesh): lo, hi corners
function platformBounds() {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  const add = (v, stride) => {
    for (let k = 0; k + 2 < v.length; k += stride) {
      for (let a = 0; a < 3; a++) {
        lo[a] = Math.min(lo[a], v[k + a]); hi[a] = Math.max(hi[a], v[k + a]);
      }
    }
  };
  const elements = RP.static.filter((s) => s.kind === 'element');
  for (const s of elements.length ? elements : RP.static.filter((x) => !x.ground)) {
    add(s.vertices, 3);
  }
  for (const o of RP.objects) add(Array.from(o.points.slice(0, o.stride)), 3);
  return isFinite(lo[0]) ? [lo, hi] : null;
}
function fitTo(lo, hi) {
  cam.target = [0, 1, 2].map((k) => (lo[k] + hi[k]) / 2);
  const radius = 0.5 * Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  cam.dist = Math.max(0.2, 1.05 * radius / Math.sin(FOV / 2));
}
// top and front: the whole scene (the arms where they start too); fit: the platforms alone
function setView(kind) {
  if (kind === 'top') { cam.az = -Math.PI / 2; cam.el = TOP_EL; }
  if (kind === 'front') { cam.az = -Math.PI / 2; cam.el = 0.3; }
  const b = kind === 'fit' ? platformBounds() : sceneBounds();
  if (b) fitTo(b[0], b[1]);
}
function addViewButtons(invalidate) {
  const before = $('btn-reset');
  const add = (id, text, title, action) => {
    const b = el('button', { id, title }, text);
    b.addEventListener('click', () => { action(b); invalidate(); });
    before.before(b);
    return b;
  };
  add('btn-top', 'top', 'from the top, fitted to the platforms', () => setView('top'));
  add('btn-front', 'front', 'from the front, fitted to the platforms', () => setView('front'));
  add('btn-fit', 'fit', 'fit the view to the platforms', () => setView('fit'));
  if (RP.zones.length) {
    const z = add('btn-zones', 'zones', "the cell's zones", () => {
      state.zones = !state.zones;
      z.classList.toggle('on', state.zones);
    });
    z.classList.toggle('on', state.zones);
  }
  // the least of the arms' and the environment's clearances
  const least = closestMarks().sort((a, b) => a.d - b.d)[0];
  if (least) {
    add('btn-closest', 'closest', 'go to the moment of ' + least.label, () => seek(least.time));
  }
}
