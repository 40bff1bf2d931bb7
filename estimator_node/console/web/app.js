// SPDX-License-Identifier: Apache-2.0
// The operator console's page (docs/console.md): camera cards with live blobs and controls, the 3D
// view, command results. All data comes over one WebSocket from panoptes_console.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/OrbitControls.js';

const params = new URLSearchParams(location.search);
const token = params.get('token') || '';
// For tests and benchmarks: the page state, reachable from the browser's console.
const page = { connected: false, state: null, blobCounts: {}, results: [], sent: [], fps: 0, frames: 0, connects: 0,
  timing: { tracks: 0, render: 0, labels: 0 } };  // ms spent, for the benchmark
window.panoptes = page;
// ?view=3d: the 3D view alone (a wall screen; the 3D benchmark).
if (params.get('view') === '3d') document.body.classList.add('only3d');

// ---------------------------------------------------------------------------------------------
// Connection: reconnects by itself, so a restarted console is picked up without reloading.
let socket = null;
let nextRequest = 1;
const pending = new Map();  // request id -> camera card

function connect() {
  const scheme = location.protocol === 'https:' ? 'wss' : 'ws';
  socket = new WebSocket(`${scheme}://${location.host}/ws?token=${encodeURIComponent(token)}`);
  socket.onopen = () => { page.connected = true; page.connects += 1; setConnection('connected', 'green'); };
  socket.onclose = () => {
    page.connected = false;
    setConnection('reconnecting', 'red');
    setTimeout(connect, 500);
  };
  socket.onerror = () => {};  // onclose follows and reconnects
  socket.onmessage = (event) => {
    let message;
    try { message = JSON.parse(event.data); } catch { return; }
    if (message.type === 'state') onState(message);
    else if (message.type === 'command_result') onResult(message);
  };
}

function setConnection(text, light) {
  const element = document.getElementById('connection');
  element.textContent = text;
  element.className = `light ${light}`;
}

function send(card, command, args = []) {
  if (!socket || socket.readyState !== WebSocket.OPEN) { showResult(card, 'rejected', 'not connected'); return; }
  const id = nextRequest++;
  pending.set(id, card);
  socket.send(JSON.stringify({ type: 'command', id, camera: card.dataset.camera, command, args }));
  page.sent.push({ id, camera: card.dataset.camera, command, args, at: Date.now() });
  showResult(card, 'sending', `${command} ${args.join(' ')}`);
}

function onResult(message) {
  page.results.push(message);
  const card = pending.get(message.id);
  const text = message.result === 'sent' ? `${message.command} ${message.args.join(' ')}: sent, waiting for the camera`
    : `${message.result}${message.reason ? ': ' + message.reason : ''}`;
  if (card) showResult(card, message.result, text);
  if (message.result !== 'sent') pending.delete(message.id);
  const item = document.createElement('li');
  item.textContent = `#${message.id} ${card ? card.dataset.camera + ' ' : ''}${text}`;
  const list = document.getElementById('results');
  list.prepend(item);
  while (list.children.length > 20) list.lastChild.remove();
}

function showResult(card, result, text) {
  const element = card.querySelector('.result');
  element.className = `result ${result}`;
  element.textContent = text;
}

// ---------------------------------------------------------------------------------------------
// Camera cards.
const cards = new Map();

function cardFor(camera) {
  let card = cards.get(camera.id);
  if (card) return card;
  card = document.getElementById('camera-card').content.firstElementChild.cloneNode(true);
  card.dataset.camera = camera.id;
  card.querySelector('.name').textContent = camera.id;
  card.masks = [];
  const canvas = card.querySelector('canvas');
  canvas.width = 640; canvas.height = 480;
  for (const [cls, command] of [['threshold', 'set_threshold'], ['exposure', 'set_exposure'], ['gain', 'set_gain']]) {
    const input = card.querySelector(`input.${cls}`);
    const output = input.nextElementSibling;
    output.textContent = input.value;
    input.addEventListener('input', () => { output.textContent = input.value; });
    input.addEventListener('change', () => send(card, command, [Number(input.value)]));
  }
  for (const command of ['clear_masks', 'capture_background', 'clear_background', 'restart']) {
    card.querySelector(`button.${command}`).addEventListener('click', () => {
      if (command === 'clear_masks') card.masks = [];
      send(card, command);
    });
  }
  const maskButton = card.querySelector('button.mask');
  maskButton.addEventListener('click', () => maskButton.classList.toggle('active'));
  attachMaskDrawing(card, canvas, maskButton);
  const grid = document.getElementById('cameras');
  const after = [...grid.children].find((other) => other.dataset.camera > camera.id);
  grid.insertBefore(card, after || null);
  cards.set(camera.id, card);
  return card;
}

// A rectangle dragged on the image (in image pixels) becomes add_mask rect x y w h.
function attachMaskDrawing(card, canvas, button) {
  let start = null;
  const toImage = (event) => {
    const box = canvas.getBoundingClientRect();
    return [Math.round((event.clientX - box.left) * canvas.width / box.width),
            Math.round((event.clientY - box.top) * canvas.height / box.height)];
  };
  canvas.addEventListener('mousedown', (event) => { if (button.classList.contains('active')) start = toImage(event); });
  canvas.addEventListener('mousemove', (event) => { if (start) card.drag = [start, toImage(event)]; });
  canvas.addEventListener('mouseup', (event) => {
    if (!start) return;
    const end = toImage(event);
    const x = Math.max(0, Math.min(start[0], end[0])), y = Math.max(0, Math.min(start[1], end[1]));
    const w = Math.min(canvas.width, Math.max(start[0], end[0])) - x;
    const h = Math.min(canvas.height, Math.max(start[1], end[1])) - y;
    start = null; card.drag = null;
    button.classList.remove('active');
    if (w < 1 || h < 1) return;
    card.masks.push([x, y, w, h]);
    send(card, 'add_mask', ['rect', x, y, w, h]);
  });
}

const fixed = (value, digits) => (value === undefined || value === null ? '—' : Number(value).toFixed(digits));

function updateCard(camera) {
  const card = cardFor(camera);
  if (camera.geometry && camera.geometry.width > 0) {
    const canvas = card.querySelector('canvas');
    if (canvas.width !== camera.geometry.width || canvas.height !== camera.geometry.height) {
      canvas.width = camera.geometry.width; canvas.height = camera.geometry.height;
    }
  }
  const light = card.querySelector('.light');
  light.className = `light ${camera.health.light}`;
  light.title = camera.health.reason;
  card.querySelector('.reason').textContent = camera.health.reason;
  if (camera.status) card.status = camera.status;
  if (camera.usage) card.usage = camera.usage;
  const status = card.status || {};
  const usage = card.usage || {};
  const now = performance.now();
  if (card.figuresAt && now - card.figuresAt < 500) { finishCard(card, camera); return; }
  card.figuresAt = now;
  card.querySelector('.figures').textContent =
    `${fixed(status.fps, 1)} fps (received ${fixed(camera.rx_fps, 1)}) · drops ${status.drops_queue ?? '—'}+${status.drops_source ?? '—'}` +
    ` · detect p99 ${fixed(status.detect_p99_ms, 2)} ms · latency ${fixed(camera.latency_ms, 1)} ms` +
    ` · clock ${fixed(status.clock_offset_ms, 2)} ms ${fixed(status.clock_drift_ppm, 1)} ppm` +
    ` · used ${usage.utilisation === undefined ? '—' : (100 * usage.utilisation).toFixed(0) + '%'}` +
    ` (p99 ${fixed(usage.latency_p99_ms, 1)} ms) · threshold ${status.threshold ?? '—'}` +
    (status.last_error ? ` · last error: ${status.last_error}` : '');
  finishCard(card, camera);
}

function finishCard(card, camera) {
  card.dataset.blobs = String(camera.blobs.length);
  page.blobCounts[camera.id] = camera.blobs.length;
  drawBlobs(card, camera.blobs);
}

function drawBlobs(card, blobs) {
  const canvas = card.querySelector('canvas');
  const context = canvas.getContext('2d');
  context.fillStyle = '#000';
  context.fillRect(0, 0, canvas.width, canvas.height);
  const scale = canvas.width / 640;
  context.fillStyle = 'rgba(229, 72, 77, 0.25)';
  for (const [x, y, w, h] of card.masks) context.fillRect(x, y, w, h);
  if (card.drag) {
    const [[x0, y0], [x1, y1]] = card.drag;
    context.strokeStyle = '#f0b429';
    context.lineWidth = 2 * scale;
    context.strokeRect(Math.min(x0, x1), Math.min(y0, y1), Math.abs(x1 - x0), Math.abs(y1 - y0));
  }
  context.fillStyle = '#7fffd4';
  for (const [x, y, area] of blobs) {
    const radius = Math.max(5 * scale, Math.sqrt(area / Math.PI));
    context.beginPath();
    context.arc(x, y, radius, 0, 2 * Math.PI);
    context.fill();
  }
}

// ---------------------------------------------------------------------------------------------
// 3D view: z up, metres.
const canvas3d = document.getElementById('view3d');
const renderer = new THREE.WebGLRenderer({ canvas: canvas3d, antialias: false, preserveDrawingBuffer: true });
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x0b0d10);
const camera3d = new THREE.PerspectiveCamera(50, 1, 0.01, 100);
camera3d.up.set(0, 0, 1);
camera3d.position.set(8, -10, 8);
const controls = new OrbitControls(camera3d, canvas3d);
controls.target.set(0, 0, 1);
controls.update();
controls.addEventListener('change', () => { labelsDirty = true; });
const grid = new THREE.GridHelper(8, 16, 0x3b4552, 0x262c35);
grid.rotation.x = Math.PI / 2;  // the floor is z = 0
scene.add(grid);
scene.add(new THREE.AxesHelper(0.5));  // the world frame

// Names and ids are drawn on a 2D canvas over the WebGL one (one fillText each, no textures).
const overlay = document.getElementById('overlay');
const labels = new Set();
let labelsDirty = true;  // redrawn when something moved, not every frame
function label(text, color = '#dde3ea') {
  const object = new THREE.Object3D();
  object.userData.label = { text, color };
  labels.add(object);
  return object;
}
function dropLabel(object) { labels.delete(object); }
const projected = new THREE.Vector3();
function drawLabels() {
  if (!labelsDirty) return;
  labelsDirty = false;
  const width = overlay.clientWidth, height = overlay.clientHeight;
  if (overlay.width !== width || overlay.height !== height) { overlay.width = width; overlay.height = height; }
  const context = overlay.getContext('2d');
  context.clearRect(0, 0, width, height);
  context.font = '12px sans-serif';
  for (const object of labels) {
    if (!object.parent) continue;
    object.getWorldPosition(projected).project(camera3d);
    if (projected.z > 1 || Math.abs(projected.x) > 1 || Math.abs(projected.y) > 1) continue;
    context.fillStyle = object.userData.label.color;
    context.fillText(object.userData.label.text, (projected.x + 1) * width / 2 + 4, (1 - projected.y) * height / 2 - 4);
  }
}

const frusta = new Map();
function updateFrustum(camera) {
  const g = camera.geometry;
  if (!g || !g.has_pose || !(g.K[0] > 0)) return;
  const key = JSON.stringify(g);
  const existing = frusta.get(camera.id);
  if (existing && existing.key === key) return;
  if (existing) { scene.remove(existing.group); existing.group.traverse(dropLabel); }
  const [fx, fy, cx, cy] = g.K;
  const depth = 0.6;
  const corner = (u, v) => new THREE.Vector3((u - cx) / fx * depth, (v - cy) / fy * depth, depth);
  const c = [corner(0, 0), corner(g.width, 0), corner(g.width, g.height), corner(0, g.height)];
  const o = new THREE.Vector3();
  const points = [o, c[0], o, c[1], o, c[2], o, c[3], c[0], c[1], c[1], c[2], c[2], c[3], c[3], c[0]];
  const group = new THREE.Group();
  group.add(new THREE.LineSegments(new THREE.BufferGeometry().setFromPoints(points),
                                   new THREE.LineBasicMaterial({ color: 0x6fa8dc })));
  const name = label(camera.id, '#6fa8dc');
  name.position.set(0, -0.15, 0);
  group.add(name);
  const [x, y, z, w] = g.T_world_cam.q;
  group.quaternion.set(x, y, z, w);
  group.position.fromArray(g.T_world_cam.p);
  scene.add(group);
  frusta.set(camera.id, { key, group });
}

// Tracks: one Points object, short trails as line segments, an id label each.
const trailLength = 20;
const trails = new Map();  // id -> { points: [Vector3], label, seen }
const trackGeometry = new THREE.BufferGeometry();
const trackPoints = new THREE.Points(trackGeometry, new THREE.PointsMaterial({ color: 0xffd166, size: 0.06 }));
trackPoints.frustumCulled = false;  // changes every update: no bounding sphere to keep
scene.add(trackPoints);
const trailGeometry = new THREE.BufferGeometry();
const trailLines = new THREE.LineSegments(trailGeometry, new THREE.LineBasicMaterial({ color: 0x8a6d1f }));
trailLines.frustumCulled = false;
scene.add(trailLines);

function updateTracks(tracks) {
  labelsDirty = true;
  const seen = new Set();
  const positions = new Float32Array(tracks.length * 3);
  tracks.forEach(([id, x, y, z], i) => {
    positions.set([x, y, z], 3 * i);
    seen.add(id);
    let trail = trails.get(id);
    if (!trail) {
      trail = { points: [], label: label(String(id), '#ffd166') };
      scene.add(trail.label);
      trails.set(id, trail);
    }
    trail.points.push(new THREE.Vector3(x, y, z));
    if (trail.points.length > trailLength) trail.points.shift();
    trail.label.position.set(x, y, z + 0.08);
  });
  for (const [id, trail] of trails) {
    if (!seen.has(id)) { scene.remove(trail.label); dropLabel(trail.label); trails.delete(id); }
  }
  trackGeometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  let segments = 0;
  for (const trail of trails.values()) segments += Math.max(0, trail.points.length - 1);
  const lines = new Float32Array(segments * 6);
  let k = 0;
  for (const trail of trails.values()) {
    for (let i = 1; i < trail.points.length; ++i) {
      const a = trail.points[i - 1], b = trail.points[i];
      lines[k++] = a.x; lines[k++] = a.y; lines[k++] = a.z; lines[k++] = b.x; lines[k++] = b.y; lines[k++] = b.z;
    }
  }
  trailGeometry.setAttribute('position', new THREE.BufferAttribute(lines, 3));
}

const bodies = new Map();
function updateBodies(list) {
  labelsDirty = true;
  const seen = new Set();
  for (const body of list) {
    seen.add(body.name);
    let object = bodies.get(body.name);
    if (!object) {
      object = new THREE.Group();
      object.add(new THREE.AxesHelper(0.4));
      const name = label(body.name, '#ffffff');
      name.position.set(0, 0, 0.2);
      object.add(name);
      scene.add(object);
      bodies.set(body.name, object);
    }
    object.position.fromArray(body.pose.p);
    const [x, y, z, w] = body.pose.q;
    object.quaternion.set(x, y, z, w);
  }
  for (const [name, object] of bodies) if (!seen.has(name)) { scene.remove(object); object.traverse(dropLabel); bodies.delete(name); }
}

function onState(state) {
  page.state = state;
  for (const camera of state.cameras) {
    updateCard(camera);
    updateFrustum(camera);
  }
  if (!synthetic) updateTracks(state.tracks);
  updateBodies(state.bodies);
  if (state.estimator) {
    const e = state.estimator;
    document.getElementById('estimator').textContent =
      `estimator: ${e.tracks_confirmed} tracks (+${e.tracks_tentative} tentative) · update p99 ${fixed(e.update_p99_ms, 2)} ms · cpu ${fixed(e.cpu_percent, 0)}%`;
  }
  if (state.console) {
    const c = state.console;
    document.getElementById('console-stats').textContent =
      `console: ${c.clients} client(s) · ${c.snapshots_skipped} skipped · ${c.commands_forwarded} commands sent · rejected ${JSON.stringify(c.rejected)}`;
  }
}

// ?synthetic_tracks=N: N tracks moving on circles, generated in the page (the 3D benchmark).
const synthetic = Number(params.get('synthetic_tracks') || 0);
function syntheticTracks(time) {
  const tracks = [];
  for (let i = 0; i < synthetic; ++i) {
    const phase = (2 * Math.PI * i) / synthetic;
    const radius = 0.5 + 1.5 * ((i * 37) % 100) / 100;
    tracks.push([i + 1, radius * Math.cos(time * 0.5 + phase), radius * Math.sin(time * 0.5 + phase), 0.3 + 1.5 * ((i * 53) % 100) / 100, 1]);
  }
  return tracks;
}

let syntheticAt = 0;
let fpsFrames = 0;
let fpsStart = performance.now();
function render(now) {
  const width = canvas3d.clientWidth, height = canvas3d.clientHeight;
  if (canvas3d.width !== width || canvas3d.height !== height) {
    renderer.setSize(width, height, false);
    labelsDirty = true;
    camera3d.aspect = width / Math.max(1, height);
    camera3d.updateProjectionMatrix();
  }
  // Synthetic tracks change at the rate live ones arrive (the console's 30 Hz snapshots).
  const t0 = performance.now();
  if (synthetic && now - syntheticAt >= 1000 / 30) { syntheticAt = now; updateTracks(syntheticTracks(now / 1000)); }
  const t1 = performance.now();
  renderer.render(scene, camera3d);
  const t2 = performance.now();
  drawLabels();
  page.timing.tracks += t1 - t0;
  page.timing.render += t2 - t1;
  page.timing.labels += performance.now() - t2;
  page.frames += 1;
  fpsFrames += 1;
  if (now - fpsStart >= 1000) { page.fps = (fpsFrames * 1000) / (now - fpsStart); fpsFrames = 0; fpsStart = now; }
  requestAnimationFrame(render);
}

// Where a world point appears on the 3D canvas, in canvas pixels (the browser test).
page.project = (point) => {
  const v = new THREE.Vector3(...point).project(camera3d);
  return [(v.x + 1) / 2 * canvas3d.width, (1 - v.y) / 2 * canvas3d.height];
};

connect();
requestAnimationFrame(render);
