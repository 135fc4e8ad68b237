// report.html's script (see base.js): playback, the controls (slider, buttons, orbit, pan,
// zoom, keys) and start-up.
/* global $, addViewButtons, buildDetails, buildFailure, buildHeader, buildLegend, buildNow,
   buildPlots, buildRun, buildTable, buildTimeline, cam, canvas, capture, clampT, drawView,
   failurePose, fmt, focusFailure, makeView, N, plots, RE, resetCamera, setView, showFailure,
   state, T, T0, T1, updateFailureHud, updateNow, updateTable, updateTimeline */

// ---------------------------------------------------------------- interaction
const slider = $('slider');
const clock = $('clock');
const playBtn = $('play');
function render() {
  const drawn = drawView();
  updateNow();
  updateFailureHud();
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
  showFailure(-1); // a time asked for: the replay, not a failed plan's pose
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
    showFailure(-1); // playing the replay, not a failed plan's pose
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
  buildRun();
  buildLegend();
  buildFailure();
  bindControls();
  addViewButtons(invalidate);
  resetCamera();
  if (RE.failure) {
    state.t = T1; // where the compile stopped
    focusFailure();
  }
  const hash = (key) => {
    const m = new RegExp('(?:^#|&)' + key + '=([0-9.eE+-]+)').exec(location.hash);
    return m ? Number(m[1]) : null;
  };
  if (hash('t') !== null) {
    state.t = clampT(hash('t') + T0);
    showFailure(-1);
  }
  if (hash('az') !== null) cam.az = hash('az');
  if (hash('el') !== null) cam.el = Math.max(-1.45, Math.min(1.45, hash('el')));
  const view = /(?:^#|&)view=(top|front|fit)/.exec(location.hash);
  if (view) setView(view[1]);
  if (/(?:^#|&)keys=1/.test(location.hash)) {
    state.keys = true;
    $('btn-keys').classList.add('on');
  }
  const drawn = render();
  const r = canvas.getBoundingClientRect();
  document.body.dataset.canvas = [r.left + window.scrollX, r.top + window.scrollY, r.width,
    r.height].map(Math.round).join(',');
  document.body.dataset.drawn = String(drawn.shapes);
  document.body.dataset.cables = String(drawn.cables);
  document.body.dataset.objects = String(drawn.objects);
  document.body.dataset.keylabels = String(drawn.labels);
  if (RE.failure) {
    const pose = failurePose();
    document.body.dataset.failures = String(RE.failure.failures.length);
    document.body.dataset.failurePair = pose && pose.pair ? pose.pair.join(',') : '';
    document.body.dataset.failureDrawn = String(drawn.highlighted);
  }
  if (document.body.dataset.status !== 'error') document.body.dataset.status = 'ok';
}
try {
  init();
} catch (e) {
  window.ceFail('init: ' + ((e && e.stack) || e));
}
