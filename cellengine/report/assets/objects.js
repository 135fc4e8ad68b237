// report.html's script (see base.js): the lab objects (objects.yaml's containers, carried by
// the gripper holding them; a vial's cap on it) and the cell's zones (boxes where only their
// robots work), in the 3D view.
/* global addShape, ctx, linkAt, NEAR, project, rgb, RP, state */
/* exported addObjects, drawObjectLabels, drawZones */

const OBJECT_COLORS = { vial: '#38bdf8', cap: '#be123c', beaker: '#67e8f9', bottle: '#4ade80',
  box: '#c8a06a' };
const ZONE_COLORS = ['#2563eb', '#7c3aed', '#ea580c', '#0f766e', '#be185d'];
state.zones = RP.zones.length > 0;

function addObjects(V, i, f, out) {
  for (const o of RP.objects) {
    addShape(V, o, linkAt(o, i, f), rgb(OBJECT_COLORS[o.object] || '#94a3b8'), out, true);
  }
}
// each container's name above it (not its cap's)
function drawObjectLabels(V, i, f) {
  ctx.font = '10px system-ui, sans-serif';
  ctx.textAlign = 'center';
  ctx.fillStyle = '#0f172a';
  for (const o of RP.objects) {
    if (o.object === 'cap') continue;
    const p = linkAt(o, i, f);
    const top = o.kind === 'box' ? [p[0] + p[9], p[1] + p[10], p[2] + p[11]] : p.slice(3, 6);
    const q = project(V, top[0], top[1], top[2] + 0.03);
    if (q[2] >= NEAR) ctx.fillText(o.name, q[0], q[1]);
  }
  ctx.textAlign = 'start';
}
// a zone's twelve edges, dashed, and its name with its robots at a top corner
function drawZones(V) {
  if (!state.zones) return;
  ctx.lineWidth = 1.2;
  ctx.setLineDash([6, 4]);
  ctx.font = '600 11px system-ui, sans-serif';
  RP.zones.forEach((z, k) => {
    const c = ZONE_COLORS[k % ZONE_COLORS.length];
    const corner = (m) => [m & 1 ? z.max[0] : z.min[0], m & 2 ? z.max[1] : z.min[1],
      m & 4 ? z.max[2] : z.min[2]];
    const pts = [0, 1, 2, 3, 4, 5, 6, 7].map((m) => project(V, ...corner(m)));
    ctx.strokeStyle = c;
    for (let a = 0; a < 8; a++) {
      for (const bit of [1, 2, 4]) {
        const b = a | bit;
        if (b === a || pts[a][2] < NEAR || pts[b][2] < NEAR) continue;
        ctx.beginPath(); ctx.moveTo(pts[a][0], pts[a][1]); ctx.lineTo(pts[b][0], pts[b][1]);
        ctx.stroke();
      }
    }
    const at = pts[4];
    if (at[2] >= NEAR) {
      ctx.fillStyle = c;
      ctx.fillText(z.name + ' (' + z.robots.join(', ') + ')', at[0] + 4, at[1] - 4);
    }
  });
  ctx.setLineDash([]);
}
