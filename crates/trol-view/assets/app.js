// The TROL view: the A465 drawn from its URDF (/urdf), moved by the state the controller
// side sends (/state once, then /events). Lengths: mm from TROL, m in the scene (as URDF).
import * as THREE from 'three';
import { OrbitControls } from '/OrbitControls.js';

const COLOURS = ['#1f77b4', '#ff7f0e', '#2ca02c', '#d62728', '#9467bd', '#8c564b'];
const NEAR_LIMIT = 10 * Math.PI / 180;
const OUTLINE = 0xff00aa;     // the objects' edges, drawn over the gripper (a colour nothing else has)
const HISTORY_S = 10;
const TRAIL_MAX = 3000;       // points of the tool's trail kept

const host = document.getElementById('scene');
const status = document.getElementById('status');
const joints = [];          // the revolute joints' rotors, joint_1 .. joint_6
let tool0 = null;
let gripper = null;         // the tool centre point's frame: the fingers close there
let fingers = [];
const history = [];         // [time, q1..q6]
let frames = 0;

// --- the scene (WebGL may be missing: the panel works without it) ---
let renderer = null, scene = null, camera = null, controls = null;
let trail = null, trailCount = 0, target = null, table = null;
const trailPositions = new Float32Array(TRAIL_MAX * 3);
const objects = new Map();
try {
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  host.appendChild(renderer.domElement);
  scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f4f1);
  camera = new THREE.PerspectiveCamera(45, 1, 0.01, 20);
  camera.up.set(0, 0, 1);
  camera.position.set(1.7, -1.45, 1.15);
  controls = new OrbitControls(camera, renderer.domElement);
  controls.target.set(0.15, 0, 0.5);
  controls.update();
  scene.add(new THREE.HemisphereLight(0xffffff, 0x888877, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(1, -2, 3);
  scene.add(sun);
  table = new THREE.Mesh(new THREE.PlaneGeometry(2, 2),
    new THREE.MeshLambertMaterial({ color: 0xc8c2b4, side: THREE.DoubleSide }));
  scene.add(table);
  const grid = new THREE.GridHelper(2, 20, 0x999999, 0xbbbbbb);
  grid.rotation.x = Math.PI / 2;
  grid.position.z = 0.0005;
  table.add(grid);
  // One buffer for the whole trail, filled as the tool moves (a geometry rebuilt from a
  // growing list of points made three.js warn "Buffer size too small" at every update).
  const trailGeometry = new THREE.BufferGeometry();
  trailGeometry.setAttribute('position',
    new THREE.BufferAttribute(trailPositions, 3).setUsage(THREE.DynamicDrawUsage));
  trailGeometry.setDrawRange(0, 0);
  trail = new THREE.Line(trailGeometry, new THREE.LineBasicMaterial({ color: 0x2a5db0 }));
  trail.frustumCulled = false;
  scene.add(trail);
  target = new THREE.Mesh(new THREE.SphereGeometry(0.012, 16, 12),
    new THREE.MeshLambertMaterial({ color: 0xd62728, transparent: true, opacity: 0.6 }));
  target.visible = false;
  scene.add(target);
  document.body.dataset.webgl = 'ok';
} catch (e) {
  renderer = null;
  document.body.dataset.webgl = 'missing';
  status.textContent = 'no WebGL here: the panel still follows the arm';
}

function resize() {
  if (!renderer) return;
  const w = host.clientWidth, h = host.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

// --- the arm, from its URDF ---
function vec(text, n = 3) {
  const v = (text || '').trim().split(/\s+/).map(Number);
  while (v.length < n) v.push(0);
  return v;
}

function placeOrigin(obj, el) {
  if (!el) return;
  const [x, y, z] = vec(el.getAttribute('xyz'));
  const [r, p, yaw] = vec(el.getAttribute('rpy'));
  obj.position.set(x, y, z);
  obj.rotation.set(r, p, yaw, 'ZYX');   // R = Rz(yaw) Ry(pitch) Rx(roll), as URDF
}

async function loadArm() {
  const text = await (await fetch('/urdf')).text();
  const doc = new DOMParser().parseFromString(text, 'application/xml');
  const materials = {};
  for (const m of doc.querySelectorAll('robot > material')) {
    const c = vec(m.querySelector('color')?.getAttribute('rgba'), 4);
    materials[m.getAttribute('name')] = new THREE.MeshLambertMaterial({ color: new THREE.Color(c[0], c[1], c[2]) });
  }
  const links = {};
  for (const l of doc.querySelectorAll('robot > link')) {
    const g = new THREE.Group();
    g.name = l.getAttribute('name');
    for (const v of l.querySelectorAll('visual')) {
      const geo = v.querySelector('geometry > *');
      let geometry = null;
      if (geo.tagName === 'cylinder') {
        geometry = new THREE.CylinderGeometry(+geo.getAttribute('radius'), +geo.getAttribute('radius'), +geo.getAttribute('length'), 24);
        geometry.rotateX(Math.PI / 2);     // three's cylinders stand on y, URDF's on z
      } else if (geo.tagName === 'box') {
        const [a, b, c] = vec(geo.getAttribute('size'));
        geometry = new THREE.BoxGeometry(a, b, c);
      } else if (geo.tagName === 'sphere') {
        geometry = new THREE.SphereGeometry(+geo.getAttribute('radius'), 20, 14);
      }
      if (!geometry) continue;
      const name = v.querySelector('material')?.getAttribute('name');
      const mesh = new THREE.Mesh(geometry, materials[name] || new THREE.MeshLambertMaterial({ color: 0xcccccc }));
      placeOrigin(mesh, v.querySelector('origin'));
      g.add(mesh);
    }
    links[g.name] = g;
  }
  for (const j of doc.querySelectorAll('robot > joint')) {
    const parent = links[j.querySelector('parent').getAttribute('link')];
    const child = links[j.querySelector('child').getAttribute('link')];
    const origin = new THREE.Group();
    placeOrigin(origin, j.querySelector('origin'));
    const rotor = new THREE.Group();
    origin.add(rotor);
    rotor.add(child);
    parent.add(origin);
    if (j.getAttribute('type') === 'revolute') {
      const k = Number(j.getAttribute('name').replace('joint_', ''));
      joints[k - 1] = { rotor, axis: new THREE.Vector3(...vec(j.querySelector('axis')?.getAttribute('xyz'))).normalize() };
    }
  }
  tool0 = links.tool0;
  // The gripper as the simulator models it: the fingers close at the tool centre point (the
  // flange moved by the tool transform), so they are drawn there, along the tool's y axis,
  // 40 mm long and reaching 10 mm beyond it (tool x points out of the flange); a palm behind
  // them. The URDF's box beyond the flange is left out: with the tool transform it would
  // not be where the fingers close.
  for (const m of [...tool0.children]) if (m.isMesh) tool0.remove(m);
  gripper = new THREE.Group();
  tool0.add(gripper);
  const fingerMaterial = new THREE.MeshLambertMaterial({ color: 0x333333 });
  fingers = [-1, 1].map(side => {
    const f = new THREE.Mesh(new THREE.BoxGeometry(0.04, 0.008, 0.02), fingerMaterial);
    f.userData.side = side;
    f.position.set(-0.01, side * 0.025, 0);
    gripper.add(f);
    return f;
  });
  const palm = new THREE.Mesh(new THREE.BoxGeometry(0.01, 0.07, 0.03),
    new THREE.MeshLambertMaterial({ color: 0x5a5a5a }));
  palm.position.set(-0.035, 0, 0);
  gripper.add(palm);
  if (scene) scene.add(links.base_link);
}

// --- the panel ---
const jointRows = [];
function buildPanel(limits) {
  const t = document.getElementById('joints');
  t.innerHTML = '';
  for (let i = 0; i < 6; i++) {
    const tr = document.createElement('tr');
    tr.innerHTML = `<td style="color:${COLOURS[i]}">J${i + 1}</td><td class="value" id="j${i + 1}">-</td>` +
      `<td><div class="bar"><span></span></div></td><td>±${(limits[i] * 180 / Math.PI).toFixed(0)}</td>`;
    t.appendChild(tr);
    jointRows.push(tr);
  }
  document.getElementById('legend').innerHTML =
    COLOURS.map((c, i) => `<span style="color:${c}">■ J${i + 1}</span>`).join('');
}

function showObjects(list) {
  const seen = new Set();
  for (const o of list) {
    seen.add(o.name);
    let m = objects.get(o.name);
    if (!m && scene) {
      m = new THREE.Mesh(new THREE.BoxGeometry(1, 1, 1), new THREE.MeshLambertMaterial({ color: 0xe0a030 }));
      // Its edges drawn over everything: a cube held between the fingers is mostly behind
      // them and the palm, and showed as a thin sliver under the gripper.
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(new THREE.BoxGeometry(1, 1, 1)),
        new THREE.LineBasicMaterial({ color: OUTLINE, depthTest: false, transparent: true }));
      edges.renderOrder = 2;
      m.add(edges);
      // Its name on screen, beside it (placed at each frame: placeLabels).
      const label = document.createElement('div');
      label.className = 'label';
      host.appendChild(label);
      m.userData.label = label;
      scene.add(m);
      objects.set(o.name, m);
    }
    if (m) {
      m.material.color.set(o.held ? 0xd0802a : 0xe0a030);
      const w = o.width / 1000;
      m.scale.set(w, w, w);
      m.position.set(o.x / 1000, o.y / 1000, o.z / 1000 + w / 2);
      m.userData.label.textContent = o.held ? `${o.name} (held)` : o.name;
    }
  }
  for (const [name, m] of objects) {
    if (!seen.has(name)) { scene.remove(m); m.userData.label.remove(); objects.delete(name); }
  }
  // The fingers see-through while they hold something, so that what they hold shows.
  const holding = list.some(o => o.held);
  for (const f of fingers) {
    f.material.transparent = holding;
    f.material.opacity = holding ? 0.45 : 1;
  }
  document.getElementById('objects').textContent = list.length
    ? list.map(o => `${o.name}: ${o.held ? 'in the gripper' : 'resting'} at x ${fixed(o.x, 3)}, y ${fixed(o.y, 3)}, z ${fixed(o.z, 3)} mm`).join('; ')
    : 'no objects in the world';
}

function update(s) {
  frames += 1;
  document.body.dataset.frames = String(frames);
  if (!jointRows.length) buildPanel(s.limits);
  s.joints.forEach((q, i) => {
    const cell = document.getElementById(`j${i + 1}`);
    // A real controller's axis that is not homed: its counters mean nothing yet.
    if (s.homed && !s.homed[i]) {
      cell.textContent = 'not homed';
      delete cell.dataset.rad;
      jointRows[i].classList.remove('near');
      return;
    }
    if (joints[i]) joints[i].rotor.quaternion.setFromAxisAngle(joints[i].axis, q);
    cell.textContent = fixed(q * 180 / Math.PI, 3);
    cell.dataset.rad = q.toFixed(6);
    const limit = s.limits[i];
    jointRows[i].querySelector('.bar span').style.left = `${((q + limit) / (2 * limit)) * 100}%`;
    jointRows[i].classList.toggle('near', limit - Math.abs(q) < NEAR_LIMIT);
  });
  const [x, y, z, yaw, pitch, roll] = s.tcp;
  document.getElementById('tcp').textContent =
    `x ${fixed(x, 3)}, y ${fixed(y, 3)}, z ${fixed(z, 3)} mm; yaw ${degrees(yaw)}, ` +
    `pitch ${degrees(pitch)}, roll ${degrees(roll)}°`;
  // A real controller may not report the fingers (null).
  const g = s.gripper_mm;
  document.getElementById('gripper').textContent =
    g == null ? 'fingers: not reported' : `fingers ${fixed(g, 3)} mm apart`;
  if (g != null) for (const f of fingers) f.position.y = f.userData.side * (g / 2000 + 0.004);
  if (gripper && s.tool) {
    const [tx, ty, tz, tyaw, tpitch, troll] = s.tool;
    gripper.position.set(tx / 1000, ty / 1000, tz / 1000);
    gripper.rotation.set(troll, tpitch, tyaw, 'ZYX');   // R = Rz(yaw) Ry(pitch) Rx(roll)
  }
  showObjects(s.objects);
  status.textContent = `${s.moving ? 'moving' : 'still'}, t = ${s.time.toFixed(2)} s` +
    (s.reported ? ' (as the controller reports it)' : '') + (renderer ? '' : ' (no WebGL here)');
  document.body.dataset.moving = String(s.moving);
  if (scene) {
    table.position.z = s.table_z / 1000;
    addToTrail(x / 1000, y / 1000, z / 1000);
    measure(s);
    target.visible = !!s.target_tcp;
    if (s.target_tcp) target.position.set(s.target_tcp[0] / 1000, s.target_tcp[1] / 1000, s.target_tcp[2] / 1000);
  }
  history.push([s.time, ...s.joints]);
  while (history.length && history[0][0] < s.time - HISTORY_S) history.shift();
  plot();
}

// What the page drew, in numbers a test can read: how far a held object's centre is from
// the point where the fingers close, and how high the fingers' lowest point is above the
// table (mm).
function measure(s) {
  scene.updateMatrixWorld(true);
  const held = s.objects.find(o => o.held);
  document.body.dataset.held = String(!!held);
  if (!gripper) return;
  const tcp = gripper.getWorldPosition(new THREE.Vector3());
  if (held && objects.get(held.name)) {
    const m = objects.get(held.name);
    const c = m.getWorldPosition(new THREE.Vector3());
    document.body.dataset.heldOffMm = (c.distanceTo(tcp) * 1000).toFixed(2);
    document.body.dataset.heldLabel = m.userData.label.hidden ? '' : m.userData.label.textContent;
    // Where it is on the canvas (device pixels), for a test to look there.
    const p = c.clone().project(camera);
    const ratio = renderer.getPixelRatio();
    document.body.dataset.heldScreen =
      `${Math.round(((p.x + 1) / 2) * host.clientWidth * ratio)},${Math.round(((1 - p.y) / 2) * host.clientHeight * ratio)}`;
  }
  const low = Math.min(...fingers.map(f => new THREE.Box3().setFromObject(f).min.z));
  document.body.dataset.fingerLowMm = ((low - s.table_z / 1000) * 1000).toFixed(2);
}

// The tool's trail: a point each update the tool moved more than half a millimetre.
function addToTrail(x, y, z) {
  if (trailCount > 0) {
    const i = (trailCount - 1) * 3;
    const d = Math.hypot(x - trailPositions[i], y - trailPositions[i + 1], z - trailPositions[i + 2]);
    if (d < 0.0005) return;
  }
  if (trailCount === TRAIL_MAX) { trailPositions.copyWithin(0, 3); trailCount -= 1; }
  trailPositions.set([x, y, z], trailCount * 3);
  trailCount += 1;
  trail.geometry.attributes.position.needsUpdate = true;
  trail.geometry.setDrawRange(0, trailCount);
  document.body.dataset.trail = String(trailCount);
}

function plot() {
  const c = document.getElementById('plot');
  const g = c.getContext('2d');
  // The axes: joint angle in degrees (±180) on the left, seconds before now below.
  const left = 34, right = 16, top = 7, bottom = 14;
  const w = c.width - left - right, h = c.height - top - bottom;
  const yOf = rad => top + h / 2 - rad / Math.PI * (h / 2);
  g.clearRect(0, 0, c.width, c.height);
  g.font = '10px sans-serif';
  g.fillStyle = '#666';
  g.strokeStyle = '#ddd';
  g.textAlign = 'right';
  g.textBaseline = 'middle';
  for (const deg of [180, 90, 0, -90, -180]) {
    const y = yOf(deg * Math.PI / 180);
    g.beginPath(); g.moveTo(left, y); g.lineTo(left + w, y); g.stroke();
    g.fillText(`${deg}°`, left - 3, y);
  }
  g.textAlign = 'center';
  g.textBaseline = 'top';
  for (let t = -HISTORY_S; t <= 0; t += 2) {
    const x = left + (t + HISTORY_S) / HISTORY_S * w;
    g.beginPath(); g.moveTo(x, top); g.lineTo(x, top + h); g.stroke();
    g.fillText(t === 0 ? 'now' : `${t} s`, x, top + h + 2);
  }
  if (history.length < 2) return;
  const t1 = history[history.length - 1][0], t0 = t1 - HISTORY_S;
  for (let i = 0; i < 6; i++) {
    g.strokeStyle = COLOURS[i];
    g.beginPath();
    history.forEach((p, n) => {
      const px = left + (p[0] - t0) / HISTORY_S * w;
      const py = yOf(p[i + 1]);
      n ? g.lineTo(px, py) : g.moveTo(px, py);
    });
    g.stroke();
  }
}

// Each object's name beside it on the canvas (an HTML label over the scene).
function placeLabels() {
  const w = host.clientWidth, h = host.clientHeight;
  for (const m of objects.values()) {
    const p = m.getWorldPosition(new THREE.Vector3()).project(camera);
    const label = m.userData.label;
    const shown = p.z < 1 && Math.abs(p.x) <= 1 && Math.abs(p.y) <= 1;
    label.hidden = !shown;
    label.style.left = `${((p.x + 1) / 2) * w + 14}px`;
    label.style.top = `${((1 - p.y) / 2) * h - 8}px`;
  }
}

function render() {
  if (renderer) { controls.update(); renderer.render(scene, camera); placeLabels(); }
  requestAnimationFrame(render);
}

await loadArm().catch(e => { status.textContent = `cannot load the arm: ${e}`; });
const first = await fetch('/state').then(r => r.ok ? r.json() : null).catch(() => null);
if (first) update(first);
new EventSource('/events').onmessage = e => {
  lastState = JSON.parse(e.data);
  update(lastState);
};
render();

// --- the pendant (only with --control, and the token from the printed address) ---
const token = new URLSearchParams(location.hash.slice(1)).get('token');
const pendant = document.getElementById('pendant');
const result = document.getElementById('result');
let pendantCalls = 0;
// The arm as the last update showed it (for the hint after a refused jog).
let lastState = null;

// A pendant request. Its answer goes to the result line (a refusal in red) unless `quiet`:
// the location list's own refresh must not wipe the refusal it follows.
async function control(path, params = {}, method = 'POST', quiet = false) {
  const query = new URLSearchParams({ ...params, token: token || '' });
  let answer;
  try {
    const response = await fetch(`/control/${path}?${query}`, { method });
    answer = await response.json();
  } catch (e) {
    answer = { ok: false, error: `no answer: ${e}` };
  }
  if (quiet) return answer;
  const words = answer.error || `${answer.command}: ${answer.text}`;
  result.textContent = words;
  result.className = answer.ok ? '' : 'refused';
  // After Home the arm stands stretched upright at the edge of its reach: say what goes.
  const atReady = lastState && lastState.joints.every(q => Math.abs(q) < 1e-3);
  const outOfReach = !answer.ok && answer.value === -2;
  document.getElementById('hint').textContent = outOfReach && atReady
    ? 'The arm stands stretched upright (READY), at the edge of its reach: jog down (-z) first, ' +
      'or turn a joint (joint 3 by 30 degrees) to leave it.'
    : '';
  document.body.dataset.pendantResult = JSON.stringify(answer);
  pendantCalls += 1;
  document.body.dataset.pendantCalls = String(pendantCalls);
  return answer;
}

function cell(row, text) {
  const td = row.insertCell();
  td.textContent = text;
  return td;
}

// How every surface prints a pose (issue 44): `x` to `places` decimals (mm to 0.001,
// degrees to 0.001), without a minus before 0 and never with an exponent.
function fixed(x, places) {
  const t = x.toFixed(places);
  return Number(t) === 0 ? (0).toFixed(places) : t;
}
function degrees(rad) {
  return fixed(rad * 180 / Math.PI, 3);
}

let locationRefreshes = 0;
async function refreshLocations() {
  const answer = await control('locations', {}, 'GET', true);
  if (!answer.ok) {
    result.textContent = answer.error || 'the locations could not be read';
    result.className = 'refused';
  }
  const list = document.getElementById('locations');
  list.replaceChildren();
  for (const loc of answer.locations || []) {
    const row = list.insertRow();
    row.dataset.name = loc.name;
    cell(row, loc.name);
    cell(row, loc.form);
    // All six values as a person reads them: mm and degrees to 0.001 (cart), degrees
    // (joint), counts (prec).
    const v = loc.form === 'prec' ? loc.values.map(x => String(Math.round(x)))
      : loc.form === 'joint' ? loc.values.map(degrees)
      : loc.values.map((x, i) => (i < 3 ? fixed(x, 3) : degrees(x)));
    const values = cell(row, v.join(' '));
    values.className = 'values';
    const go = document.createElement('button');
    go.textContent = 'move to';
    go.dataset.move = loc.name;
    go.onclick = () => control('move', { name: loc.name });
    cell(row, '').appendChild(go);
    const del = document.createElement('button');
    del.textContent = 'delete';
    del.dataset.delete = loc.name;
    del.onclick = async () => { await control('delete', { name: loc.name }); refreshLocations(); };
    cell(row, '').appendChild(del);
  }
  locationRefreshes += 1;
  document.body.dataset.locationRefreshes = String(locationRefreshes);
}

async function startPendant() {
  let on = false;
  try {
    on = (await (await fetch('/control')).json()).control === true;
  } catch (e) {
    on = false;
  }
  document.body.dataset.control = String(on && !!token);
  if (!on || !token) return;
  pendant.hidden = false;
  const halt = document.getElementById('halt');
  halt.hidden = false;
  halt.onclick = () => control('halt');
  const frame = () => document.getElementById('jog-frame').value;
  const straight = () => (document.getElementById('jog-straight').checked ? 1 : 0);
  for (const b of pendant.querySelectorAll('[data-jog]')) {
    b.onclick = () => {
      const [axis, sign] = b.dataset.jog.split(',');
      const step = Number(document.getElementById('jog-step').value) * Number(sign);
      // World: TROLJog; the tool's frame: TROLDepart.
      control(frame() === 'tool' ? 'depart' : 'jog', { [`d${axis}`]: step, straight: straight() });
    };
  }
  const worldAxis = { yaw: 'z', pitch: 'y', roll: 'x' };
  for (const b of pendant.querySelectorAll('[data-turn]')) {
    b.onclick = () => {
      const [angle, sign] = b.dataset.turn.split(',');
      const deg = Number(document.getElementById('turn-step').value) * Number(sign);
      // World: about the world's axis through the tool tip; the tool's frame: TROLDepart.
      if (frame() === 'tool') control('depart', { [`d${angle}`]: deg * Math.PI / 180, straight: straight() });
      else control('turn', { axis: worldAxis[angle], degrees: deg, straight: straight() });
    };
  }
  const force = () => document.getElementById('grip-force').value;
  document.getElementById('grip-open').onclick = () => control('open', { force: force() });
  document.getElementById('grip-close').onclick = () => control('close', { force: force() });
  document.getElementById('grip-to').onclick = () =>
    control('grip', { mm: document.getElementById('grip-mm').value });
  for (const b of pendant.querySelectorAll('[data-joint]')) {
    b.onclick = () => {
      const deg = Number(document.getElementById('joint-step').value) * Number(b.dataset.joint);
      control('joint', { joint: document.getElementById('joint-num').value, radians: deg * Math.PI / 180 });
    };
  }
  document.getElementById('speed-set').onclick = () =>
    control('speed', { percent: document.getElementById('speed').value });
  document.getElementById('home').onclick = () => control('home');
  document.getElementById('here').onclick = async () => {
    await control('here', {
      name: document.getElementById('here-name').value,
      form: document.getElementById('here-form').value,
    });
    refreshLocations();
  };
  document.getElementById('loc-refresh').onclick = refreshLocations;
  document.getElementById('loc-save').onclick = () => control('save');
  refreshLocations();
}
startPendant();
