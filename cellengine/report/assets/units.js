// report.html's script (see base.js): units per joint type. A prismatic joint's value is a
// length, shown in mm and mm/s; a revolute joint's an angle, in deg and deg/s (the replay
// carries m and rad).
/* global RP */
/* exported jointKind, JOINT_UNITS, jointUnit */

const JOINT_UNITS = {
  prismatic: { pos: 'mm', vel: 'mm/s', k: 1000 },
  revolute: { pos: 'deg', vel: 'deg/s', k: 180 / Math.PI },
};
function jointKind(j) {
  return (RP.joint_kinds || [])[j] === 'prismatic' ? 'prismatic' : 'revolute';
}
function jointUnit(j) { return JOINT_UNITS[jointKind(j)]; }
