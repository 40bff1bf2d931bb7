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
  socket.onopen = () => {
    page.connected = true; page.connects += 1; setConnection('connected', 'green');
    if (selected) socket.send(JSON.stringify({ type: 'select', kind: selected.kind, key: selected.key }));
  };
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
    else if (message.type === 'details') onDetails(message);
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

// A recorder command: start (with a file name) or stop; the row shows the outcome as a card does.
function sendRecorder(row, command, name = '') {
  if (!socket || socket.readyState !== WebSocket.OPEN) { showResult(row, 'rejected', 'not connected'); return; }
  const id = nextRequest++;
  pending.set(id, row);
  socket.send(JSON.stringify({ type: 'recorder', id, recorder: row.dataset.recorder, command, name }));
  page.sent.push({ id, recorder: row.dataset.recorder, command, args: [name], at: Date.now() });
  showResult(row, 'sending', `${command} ${name}`);
}

function onResult(message) {
  page.results.push(message);
  const card = pending.get(message.id);
  const waiting = message.recorder ? 'recorder' : message.body ? 'body maker (panoptes_ctl body create)' : 'camera';
  let text = message.result === 'sent' ? `${message.command} ${message.args.join(' ')}: sent, waiting for the ${waiting}`
    : `${message.result}${message.reason ? ': ' + message.reason : ''}`;
  if (card === newBodyResult && message.result === 'applied') text = bodyCreated(message.reason);
  if (card) showResult(card, message.result, text);
  if (message.result !== 'sent') pending.delete(message.id);
  const item = document.createElement('li');
  const target = card ? (card.dataset.camera || card.dataset.recorder || card.dataset.body) + ' ' : '';
  item.textContent = `#${message.id} ${target}${text}`;
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
    // While the user moves a slider (and for a while after, until the camera's status reports the
    // new value) the status does not move it back.
    input.addEventListener('input', () => { output.textContent = input.value; input.touchedAt = performance.now(); });
    input.addEventListener('change', () => { input.touchedAt = performance.now(); send(card, command, [Number(input.value)]); });
  }
  for (const command of ['clear_masks', 'capture_background', 'clear_background', 'restart']) {
    card.querySelector(`button.${command}`).addEventListener('click', () => {
      if (command === 'clear_masks') card.masks = [];
      send(card, command);
    });
  }
  card.querySelector('button.preview').addEventListener('click', () => send(card, 'preview', [640]));
  const maskButton = card.querySelector('button.mask');
  const polygonButton = card.querySelector('button.polygon');
  maskButton.addEventListener('click', () => { maskButton.classList.toggle('active'); polygonButton.classList.remove('active'); card.polygon = null; });
  polygonButton.addEventListener('click', () => { polygonButton.classList.toggle('active'); maskButton.classList.remove('active'); card.polygon = null; });
  attachMaskDrawing(card, canvas, maskButton);
  attachPolygonDrawing(card, canvas, polygonButton);
  const grid = document.getElementById('cameras');
  const after = [...grid.children].find((other) => other.dataset.camera > camera.id);
  grid.insertBefore(card, after || null);
  cards.set(camera.id, card);
  return card;
}

// A rectangle dragged on the image (in image pixels) becomes add_mask rect x y w h.
function attachMaskDrawing(card, canvas, button) {
  let start = null;
  const toImage = (event) => toImagePoint(canvas, event);
  // The drag is followed on the whole window: a release beyond the image's edge masks up to the
  // edge, and a card whose text re-wraps under the pointer (a health reason appearing) still ends
  // the drag it started.
  canvas.addEventListener('mousedown', (event) => { if (button.classList.contains('active')) start = toImage(event); });
  window.addEventListener('mousemove', (event) => { if (start) card.drag = [start, toImage(event)]; });
  window.addEventListener('mouseup', (event) => {
    if (!start) return;
    const end = toImage(event);
    const x = Math.max(0, Math.min(start[0], end[0])), y = Math.max(0, Math.min(start[1], end[1]));
    const w = Math.min(canvas.width, Math.max(start[0], end[0])) - x;
    const h = Math.min(canvas.height, Math.max(start[1], end[1])) - y;
    start = null; card.drag = null;
    button.classList.remove('active');
    if (w < 1 || h < 1) return;
    card.masks.push([[x, y], [x + w, y], [x + w, y + h], [x, y + h]]);
    send(card, 'add_mask', ['rect', x, y, w, h]);
  });
}

const toImagePoint = (canvas, event) => {
  const box = canvas.getBoundingClientRect();
  return [Math.round((event.clientX - box.left) * canvas.width / box.width),
          Math.round((event.clientY - box.top) * canvas.height / box.height)];
};

// Corners clicked on the image (in image pixels); clicking near the first corner again, or a
// double-click, closes the polygon into add_mask poly x1 y1 x2 y2 ... (camera_node's mask kind).
function attachPolygonDrawing(card, canvas, button) {
  const close = () => {
    const points = card.polygon || [];
    card.polygon = null; card.hover = null;
    button.classList.remove('active');
    if (points.length < 3) return;
    card.masks.push(points);
    send(card, 'add_mask', ['poly', ...points.flat()]);
  };
  canvas.addEventListener('click', (event) => {
    if (!button.classList.contains('active')) return;
    const point = toImagePoint(canvas, event).map((v, i) => Math.max(0, Math.min(i ? canvas.height - 1 : canvas.width - 1, v)));
    card.polygon = card.polygon || [];
    const first = card.polygon[0];
    const near = 12 * canvas.width / canvas.getBoundingClientRect().width;
    if (first && card.polygon.length >= 3 && Math.hypot(point[0] - first[0], point[1] - first[1]) < near) { close(); return; }
    card.polygon.push(point);
    if (card.polygon.length >= 32) close();
  });
  canvas.addEventListener('dblclick', () => { if (button.classList.contains('active')) close(); });
  canvas.addEventListener('mousemove', (event) => { if (card.polygon) card.hover = toImagePoint(canvas, event); });
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
  card.querySelector('.reason').title = camera.health.reason;  // the heading ends in an ellipsis
  if (camera.status) card.status = camera.status;
  if (camera.usage) card.usage = camera.usage;
  if (camera.status_age_s !== undefined) card.statusAge = camera.status_age_s;
  const usage = card.usage || {};
  const now = performance.now();
  if (card.figuresAt && now - card.figuresAt < 500) { finishCard(card, camera); return; }
  card.figuresAt = now;
  // A camera's own figures come with its status, once a second: older than 3 s they are not
  // what the camera does now and are not shown as if they were.
  const stale = card.statusAge !== undefined && card.statusAge > 3;
  const status = stale ? {} : card.status || {};
  if (!stale) syncSliders(card, status);
  const figures = card.querySelector('.figures');
  figures.replaceChildren(...cardFigures(camera, status, usage).map(([text, help]) => {
    const span = document.createElement('span');
    span.textContent = text;
    span.title = help;
    return span;
  }));
  if (stale) figures.prepend(Object.assign(document.createElement('b'), { className: 'stale', textContent: `status ${card.statusAge.toFixed(0)} s old · `, title: figureHelp.stale[1] }));
  finishCard(card, camera);
}

// What each figure on a camera card means: its tooltip, and the legend under the page.
const figureHelp = {
  fps: ['fps (received)', 'frames per second the camera detects, and that reach this console over DDS'],
  drops: ['drops a+b', 'frames the camera node dropped since it started: because its detector queue was full + because the source (driver) lost them'],
  detect: ['detect p99', "99th percentile of the camera node's threshold-and-centroid time per frame"],
  latency: ['latency', "a frame's arrival at this console minus its exposure stamp, smoothed"],
  clock: ['clock', "the camera clock's offset (ms) and drift (ppm) against the estimator's time base"],
  used: ['used (p99)', "share of this camera's frames the estimator used in its update (the rest came too late or were dropped), and the 99th percentile of their stamp-to-update latency"],
  lost: ['estimator: lost N s', 'no frame from this camera has reached the estimator for N seconds (more than its node.camera_lost_after_s): it is not tracking with it'],
  calibration: ['calibration', "the estimator's check of this camera against the tracks the other cameras see (docs/continuous_calibration.md): ok, small bias (still used), quarantined (its blobs are not used: bumped or moved), unknown (too few tracks to judge); hover for the reason"],
  refused: ['2nd writer refused', "frames another camera node sent under this camera's id: the estimator refuses them (it keeps the first writer)"],
  threshold: ['threshold', 'the blob threshold the camera reports using (0-255)'],
  error: ['last error', "the camera node's last error"],
  stale: ['status N s old', "the camera's own figures are older than 3 s (a stopped or unreachable node) and are not shown"],
};

// The estimator's view of the cameras (issue 34): how many are live, which are lost and since when,
// tracks it only predicts, and camera ids a second writer claimed.
function estimatorCameras(e) {
  const total = (e.cameras_live ?? 0) + (e.cameras_lost ?? 0);
  if (!total) return '';
  let text = ` · cameras ${e.cameras_live}/${total} live`;
  if (e.lost?.length) text += ' (lost: ' + e.lost.map((c) => `${c.id} ${fixed(c.since_s, 1)} s`).join(', ') + ')';
  if (e.tracks_unobserved) text += ` · no camera live: ${e.tracks_unobserved} tracks predicted only`;
  if (e.refused?.length) text += ' · 2nd writer refused for ' + e.refused.map((c) => `${c.id} (${c.frames} frames)`).join(', ');
  return text;
}

// A camera's calibration health as a light and a word; the reason is the figure's title (hover).
const calibrationLights = { ok: '🟢 ok', small_bias: '🟡 small bias', quarantined: '🔴 quarantined', unknown: '⚪ unknown' };
function calibrationLight(c) {
  const text = calibrationLights[c.state] || c.state;
  return c.reason ? `${text} (${c.reason})` : text;
}

function cardFigures(camera, status, usage) {
  const used = usage.utilisation === undefined ? '—' : (100 * usage.utilisation).toFixed(0) + '%';
  return [
    [`${fixed(status.fps, 1)} fps (received ${fixed(camera.rx_fps, 1)})`, 'fps'],
    [` · drops ${status.drops_queue ?? '—'}+${status.drops_source ?? '—'}`, 'drops'],
    [` · detect p99 ${fixed(status.detect_p99_ms, 2)} ms`, 'detect'],
    [` · latency ${fixed(camera.latency_ms, 1)} ms`, 'latency'],
    [` · clock ${fixed(status.clock_offset_ms, 2)} ms ${fixed(status.clock_drift_ppm, 1)} ppm`, 'clock'],
    usage.state === 'lost' ? [` · estimator: lost ${fixed(usage.since_last_frame_s, 1)} s`, 'lost']
      : [` · used ${used} (p99 ${fixed(usage.latency_p99_ms, 1)} ms)`, 'used'],
    ...(usage.refused_frames ? [[` · 2nd writer refused (${usage.refused_frames} frames)`, 'refused']] : []),
    ...(usage.calibration ? [[` · calibration ${calibrationLight(usage.calibration)}`, 'calibration']] : []),
    [` · threshold ${status.threshold ?? '—'}`, 'threshold'],
    ...(status.last_error ? [[` · last error: ${status.last_error}`, 'error']] : []),
  ].map(([text, key]) => [text, figureHelp[key][1]]);
}

function fillLegend() {
  const list = document.querySelector('#legend dl');
  for (const [term, help] of Object.values(figureHelp)) {
    list.append(Object.assign(document.createElement('dt'), { textContent: term }),
                Object.assign(document.createElement('dd'), { textContent: help }));
  }
}
fillLegend();

// The sliders show the camera's own settings, except one the user moved in the last 3 s.
function syncSliders(card, status) {
  for (const [cls, value] of [['threshold', status.threshold], ['exposure', status.exposure_us], ['gain', status.gain_db]]) {
    if (value === undefined || value === null) continue;
    const input = card.querySelector(`input.${cls}`);
    if (document.activeElement === input || (input.touchedAt && performance.now() - input.touchedAt < 3000)) continue;
    if (Number(input.value) !== Number(value)) {
      input.value = String(value);
      input.nextElementSibling.textContent = input.value;
    }
  }
}

function finishCard(card, camera) {
  if (camera.preview_stamp_ns && String(camera.preview_stamp_ns) !== card.dataset.previewStamp) {
    card.dataset.previewStamp = String(camera.preview_stamp_ns);
    loadPreview(card, camera.id);
  }
  card.dataset.blobs = String(camera.blobs.length);
  page.blobCounts[camera.id] = camera.blobs.length;
  drawBlobs(card, camera.blobs, camera.windows || []);
}

// The camera's preview (a PGM from /api/preview/<id>) becomes the card's background image.
async function loadPreview(card, id) {
  const response = await fetch(`/api/preview/${encodeURIComponent(id)}`, { cache: 'no-store' });
  if (!response.ok) return;
  const bytes = new Uint8Array(await response.arrayBuffer());
  let offset = 0;
  const fields = [];
  while (fields.length < 4 && offset < bytes.length) {  // P5, width, height, maxval
    while (offset < bytes.length && /\s/.test(String.fromCharCode(bytes[offset]))) ++offset;
    let field = '';
    while (offset < bytes.length && !/\s/.test(String.fromCharCode(bytes[offset]))) field += String.fromCharCode(bytes[offset++]);
    fields.push(field);
  }
  ++offset;  // the single whitespace after maxval
  const [magic, width, height] = [fields[0], Number(fields[1]), Number(fields[2])];
  if (magic !== 'P5' || !(width > 0 && height > 0) || bytes.length - offset < width * height) return;
  const image = new ImageData(width, height);
  for (let i = 0; i < width * height; ++i) {
    const v = bytes[offset + i];
    image.data.set([v, v, v, 255], 4 * i);
  }
  card.preview = await createImageBitmap(image);
  card.dataset.previewShown = card.dataset.previewStamp;
}

function drawBlobs(card, blobs, windows = []) {
  const canvas = card.querySelector('canvas');
  const context = canvas.getContext('2d');
  context.fillStyle = '#000';
  context.fillRect(0, 0, canvas.width, canvas.height);
  if (card.preview) context.drawImage(card.preview, 0, 0, canvas.width, canvas.height);
  const scale = canvas.width / 640;
  context.fillStyle = 'rgba(229, 72, 77, 0.25)';
  for (const points of card.masks) {
    context.beginPath();
    points.forEach(([x, y], i) => (i ? context.lineTo(x, y) : context.moveTo(x, y)));
    context.closePath();
    context.fill();
  }
  if (card.polygon && card.polygon.length) {
    context.strokeStyle = '#f0b429';
    context.lineWidth = 2 * scale;
    context.beginPath();
    card.polygon.forEach(([x, y], i) => (i ? context.lineTo(x, y) : context.moveTo(x, y)));
    if (card.hover) context.lineTo(...card.hover);
    context.stroke();
    context.fillStyle = '#f0b429';
    for (const [x, y] of card.polygon) context.fillRect(x - 3 * scale, y - 3 * scale, 6 * scale, 6 * scale);
  }
  if (card.drag) {
    const [[x0, y0], [x1, y1]] = card.drag;
    context.strokeStyle = '#f0b429';
    context.lineWidth = 2 * scale;
    context.strokeRect(Math.min(x0, x1), Math.min(y0, y1), Math.abs(x1 - x0), Math.abs(y1 - y0));
  }
  // The estimator's predicted windows for the next frame (where camera_node searches first).
  context.strokeStyle = 'rgba(120, 160, 255, 0.9)';
  context.lineWidth = 1.5 * scale;
  context.setLineDash([4 * scale, 3 * scale]);
  for (const [x, y, halfWidth, halfHeight] of windows) context.strokeRect(x - halfWidth, y - halfHeight, 2 * halfWidth, 2 * halfHeight);
  context.setLineDash([]);
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
// A label of higher priority is drawn first; one that would overlap a label already drawn is left
// out (issue 32: track ids were drawn over the body names).
const labelPriority = { track: 0, camera: 1, body: 2, chain: 2 };
function label(text, color = '#dde3ea', priority = labelPriority.camera) {
  const object = new THREE.Object3D();
  object.userData.label = { text, color, priority };
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
  context.lineWidth = 3;
  context.strokeStyle = 'rgba(17, 20, 24, 0.85)';  // a dark outline keeps text readable over points
  const ordered = [...labels].filter((object) => object.parent && object.visible)
    .sort((a, b) => b.userData.label.priority - a.userData.label.priority);
  const drawn = [];
  page.labelsHidden = 0;
  for (const object of ordered) {
    object.getWorldPosition(projected).project(camera3d);
    if (projected.z > 1 || Math.abs(projected.x) > 1 || Math.abs(projected.y) > 1) continue;
    const { text, color } = object.userData.label;
    const box = { x: (projected.x + 1) * width / 2 + 4, y: (1 - projected.y) * height / 2 - 4, w: context.measureText(text).width, h: 12 };
    if (drawn.some((d) => box.x < d.x + d.w && d.x < box.x + box.w && box.y - box.h < d.y && d.y - d.h < box.y)) {
      ++page.labelsHidden;
      continue;
    }
    drawn.push(box);
    context.strokeText(text, box.x, box.y);
    context.fillStyle = color;
    context.fillText(text, box.x, box.y);
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
// A fixed size on screen: 6 cm attenuated by distance was 1-2 px from across a room (issue 32).
const trackPoints = new THREE.Points(trackGeometry, new THREE.PointsMaterial({ color: 0xffd166, size: 7, sizeAttenuation: false }));
trackPoints.frustumCulled = false;  // changes every update: no bounding sphere to keep
scene.add(trackPoints);
// The tracks picked for a new body (shift+click), drawn larger over them.
const pickedGeometry = new THREE.BufferGeometry();
const pickedPoints = new THREE.Points(pickedGeometry, new THREE.PointsMaterial({ color: 0x00e5ff, size: 13, sizeAttenuation: false, depthTest: false }));
pickedPoints.frustumCulled = false;
pickedPoints.renderOrder = 2;
scene.add(pickedPoints);
const trailGeometry = new THREE.BufferGeometry();
const trailLines = new THREE.LineSegments(trailGeometry, new THREE.LineBasicMaterial({ color: 0x8a6d1f }));
trailLines.frustumCulled = false;
scene.add(trailLines);

// Names of subjects' markers (rt/panoptes/labels, docs/marker_sets.md): track id -> "R.ASIS"
// ("s1:R.ASIS" with several subjects), and the marker set's sticks between named markers.
let markerNames = new Map();
function namesOf(subjects) {
  const names = new Map();
  for (const s of subjects) {
    for (const [id, name] of Object.entries(s.names || {})) names.set(Number(id), subjects.length > 1 ? `${s.name}:${name}` : name);
  }
  return names;
}
const stickGeometry = new THREE.BufferGeometry();
const stickLines = new THREE.LineSegments(stickGeometry, new THREE.LineBasicMaterial({ color: 0x9ad1ff }));
stickLines.frustumCulled = false;
scene.add(stickLines);
function updateSticks(subjects, tracks) {
  const at = new Map(tracks.map(([id, x, y, z]) => [id, [x, y, z]]));
  const segments = [];
  for (const s of subjects) {
    const byName = new Map();
    for (const [id, name] of Object.entries(s.names || {})) if (at.has(Number(id))) byName.set(name, at.get(Number(id)));
    for (const [a, b] of s.sticks || []) if (byName.has(a) && byName.has(b)) segments.push(...byName.get(a), ...byName.get(b));
  }
  page.sticksDrawn = segments.length / 6;
  stickGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(segments), 3));
}

function updateTracks(tracks) {
  labelsDirty = true;
  const seen = new Set();
  const positions = new Float32Array(tracks.length * 3);
  tracks.forEach(([id, x, y, z], i) => {
    positions.set([x, y, z], 3 * i);
    seen.add(id);
    let trail = trails.get(id);
    if (!trail) {
      trail = { points: [], label: label(String(id), '#ffd166', labelPriority.track) };
      scene.add(trail.label);
      trails.set(id, trail);
    }
    trail.points.push(new THREE.Vector3(x, y, z));
    if (trail.points.length > trailLength) trail.points.shift();
    trail.label.position.set(x, y, z + 0.08);
    trail.label.userData.label.text = markerNames.get(id) || String(id);
  });
  for (const [id, trail] of trails) {
    if (!seen.has(id)) { scene.remove(trail.label); dropLabel(trail.label); trails.delete(id); }
  }
  page.trackLabels = trails;  // track id -> { label }: the text drawn beside each track (tests)
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
      // Drawn over the tracks' 7 px points: the body's own markers sit around its origin and hid
      // most of its axes there (issue 37: the console test found 1 axis pixel near a body).
      const axes = new THREE.AxesHelper(0.4);
      axes.material.depthTest = false;
      axes.renderOrder = 10;
      object.add(axes);
      const name = label(body.name, '#ffffff', labelPriority.body);
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

// Articulated chains (rt/panoptes/chains, docs/articulated.md): the joints linked by segments,
// valid markers filled and bright, invalid ones (not updated lately) small and grey, the tip and
// the tip predicted ahead joined by a dashed line. Grabbing turns the bones and the tip magenta.
// Drawn over everything else (no depth test): the finger is small beside the tracks' points.
const chainColours = { bone: 0x4dd0e1, grab: 0xff00ff, tip: 0x00ff80, predicted: 0xffa000, valid: 0xf0f0f0, invalid: 0x59626c };
const chains = new Map();  // name -> { group, bones, valid, invalid, tip, predicted, ahead, label }
function chainObject(name) {
  const onTop = (object, order) => { object.renderOrder = order; object.material.depthTest = false; object.frustumCulled = false; return object; };
  // Drawn in this order: bones, markers, predicted tip, tip (the tip is never hidden).
  const points = (colour, size, order) => onTop(new THREE.Points(new THREE.BufferGeometry(),
    new THREE.PointsMaterial({ color: colour, size, sizeAttenuation: false })), order);
  const chain = {
    group: new THREE.Group(),
    bones: onTop(new THREE.LineSegments(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: chainColours.bone })), 10),
    ahead: onTop(new THREE.LineSegments(new THREE.BufferGeometry(),
      new THREE.LineDashedMaterial({ color: chainColours.predicted, dashSize: 0.004, gapSize: 0.003 })), 10),
    valid: points(chainColours.valid, 7, 11),
    invalid: points(chainColours.invalid, 4, 11),
    predicted: points(chainColours.predicted, 8, 12),
    tip: points(chainColours.tip, 10, 13),
    label: label(name, '#4dd0e1', labelPriority.chain),
  };
  chain.group.add(chain.bones, chain.ahead, chain.valid, chain.invalid, chain.predicted, chain.tip, chain.label);
  scene.add(chain.group);
  return chain;
}
const setPoints = (object, points) => {
  object.geometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(points.flat()), 3));
  object.geometry.computeBoundingSphere();
};
function updateChains(list) {
  labelsDirty = true;
  const seen = new Set();
  for (const c of list) {
    seen.add(c.name);
    let chain = chains.get(c.name);
    if (!chain) { chain = chainObject(c.name); chains.set(c.name, chain); }
    const tracking = c.status === 'tracking' && c.markers;
    chain.group.visible = Boolean(tracking);
    chain.label.visible = Boolean(tracking);
    chain.label.userData.label.text = `${c.name}${c.grabbing ? ' · grab' : ''}`;
    chain.label.userData.label.color = c.grabbing ? '#ff00ff' : '#4dd0e1';
    if (!tracking) continue;
    const bones = [];
    for (let i = 1; i < c.markers.length; ++i) bones.push(c.markers[i - 1], c.markers[i]);
    bones.push(c.markers.at(-1), c.tip);
    setPoints(chain.bones, bones);
    chain.bones.material.color.setHex(c.grabbing ? chainColours.grab : chainColours.bone);
    setPoints(chain.valid, c.markers.filter((_, i) => c.valid[i]));
    setPoints(chain.invalid, c.markers.filter((_, i) => !c.valid[i]));
    setPoints(chain.tip, [c.tip]);
    chain.tip.material.color.setHex(c.grabbing ? chainColours.grab : chainColours.tip);
    setPoints(chain.predicted, [c.predicted_tip]);
    setPoints(chain.ahead, [c.tip, c.predicted_tip]);
    chain.ahead.computeLineDistances();
    chain.label.position.set(c.tip[0], c.tip[1], c.tip[2] + 0.01);
  }
  for (const [name, chain] of chains) {
    if (!seen.has(name)) { scene.remove(chain.group); chain.group.traverse(dropLabel); chains.delete(name); }
  }
  updateChainLegend(list);
}

// The list beside the view: name, status, grab state and counts; a click selects the chain (its
// figures, joint angles included) and brings the view to it.
function updateChainLegend(list) {
  const legend = document.getElementById('chains');
  if (legend.hidden !== (list.length === 0)) legend.hidden = list.length === 0;
  const items = legend.querySelector('ul');
  for (const c of list) {
    let item = items.querySelector(`li[data-chain="${CSS.escape(c.name)}"]`);
    if (!item) {
      item = document.createElement('li');
      item.dataset.chain = c.name;
      item.addEventListener('click', () => { select('chain', c.name); focusChain(c.name); });
      items.append(item);
    }
    const text = `${c.name}: ${c.status.replace('_', ' ')}${c.grabbing ? ' · grabbing' : ''} · ${c.grabs} grabs, ${c.releases} releases`;
    if (item.textContent === text) continue;  // 30 snapshots a second: touch the page only on a change
    item.className = c.grabbing ? 'grabbing' : c.status;
    item.textContent = text;
  }
  for (const item of [...items.children]) if (!list.some((c) => c.name === item.dataset.chain)) item.remove();
}

// Orbit around `target` from `distance` m, keeping the direction the view looks from.
function focusOn(target, distance) {
  const direction = camera3d.position.clone().sub(controls.target).normalize();
  controls.target.copy(target);
  camera3d.position.copy(target).addScaledVector(direction, distance);
  controls.update();
  labelsDirty = true;
}
page.focusOn = (point, distance) => focusOn(new THREE.Vector3(...point), distance);

// Orbit around the chain's tip from 0.4 m.
function focusChain(name) {
  const c = page.state && page.state.chains.find((chain) => chain.name === name);
  if (!c || !c.tip) return;
  focusOn(new THREE.Vector3(...c.tip), 0.4);
}

// ---------------------------------------------------------------------------------------------
// Click a track or body in the 3D view: the console sends its figures ~5 times a second.
let selected = null;  // { kind: 'track' | 'body' | 'chain', key }
const details = document.getElementById('details');
function select(kind, key) {
  selected = kind ? { kind, key: String(key) } : null;
  page.selected = selected;
  details.hidden = !selected;
  if (selected) { details.querySelector('h3').textContent = `${kind} ${key}`; details.querySelector('table').textContent = ''; }
  if (socket && socket.readyState === WebSocket.OPEN)
    socket.send(JSON.stringify({ type: 'select', kind: selected ? selected.kind : '', key: selected ? selected.key : '' }));
}
details.querySelector('.close').addEventListener('click', () => select(null));

// The nearest track or body to the click on screen, within 15 px (bodies first: they are larger).
let downAt = null;
canvas3d.addEventListener('pointerdown', (event) => { downAt = [event.clientX, event.clientY]; });
canvas3d.addEventListener('pointerup', (event) => {
  if (!downAt || Math.hypot(event.clientX - downAt[0], event.clientY - downAt[1]) > 4) return;  // a drag orbits
  const box = canvas3d.getBoundingClientRect();
  const x = (event.clientX - box.left) * canvas3d.width / box.width, y = (event.clientY - box.top) * canvas3d.height / box.height;
  const candidates = [];
  for (const body of (page.state ? page.state.bodies : [])) candidates.push(['body', body.name, body.pose.p, 0]);
  for (const chain of (page.state ? page.state.chains || [] : [])) {
    for (const point of chain.tip ? [chain.tip, ...chain.markers] : []) candidates.push(['chain', chain.name, point, 0]);
  }
  for (const [id, px, py, pz] of (page.state ? page.state.tracks : [])) candidates.push(['track', id, [px, py, pz], 4]);
  let best = null;
  for (const [kind, key, point, penalty] of candidates) {
    const [u, v] = page.project(point);
    const distance = Math.hypot(u - x, v - y) + penalty;
    if (distance < 15 && (!best || distance < best[2])) best = [kind, key, distance];
  }
  if (best && best[0] === 'track' && event.shiftKey) toggleBodyTrack(best[1]);
  else if (best) select(best[0], best[1]);
});

// ---------------------------------------------------------------------------------------------
// Bodies from markers (docs/console.md, "Bodies from markers"): shift+click tracks, name the body,
// choose its pivot and create it. The console runs panoptes_ctl body create, which averages the
// tracks over 30 frames and appends the body to the estimator's bodies file (panoptes_console
// --bodies); the estimator reloads it and the body appears in the view.
const bodyTracks = [];  // track ids, in the order picked
const newBody = document.getElementById('newbody');
const newBodyResult = { dataset: { body: 'body' }, querySelector: () => newBody.querySelector('.result') };
page.bodyTracks = bodyTracks;
function toggleBodyTrack(id) {
  const at = bodyTracks.indexOf(id);
  if (at >= 0) bodyTracks.splice(at, 1); else bodyTracks.push(id);
  showBodyTracks();
}
function showBodyTracks() {
  newBody.hidden = bodyTracks.length === 0;
  newBody.querySelector('.tracks').textContent = bodyTracks.join(', ') + (bodyTracks.length < 3 ? ` (${3 - bodyTracks.length} more)` : '');
  const pivot = document.getElementById('newbody-pivot');
  const chosen = pivot.value;
  pivot.textContent = '';
  pivot.add(new Option('centroid', ''));
  for (const id of bodyTracks) pivot.add(new Option(`track ${id}`, String(id)));
  pivot.value = bodyTracks.includes(Number(chosen)) ? chosen : '';
  document.getElementById('newbody-create').disabled = bodyTracks.length < 3;
  updatePicked();
}
// The body maker's line ({body, tracks, frames, markers, file}) as a sentence (Clear drops the picks).
function bodyCreated(line) {
  let made;
  try { made = JSON.parse(line); } catch { return `applied: ${line}`; }
  page.createdBody = made;
  return `applied: body ${made.body} from tracks ${made.tracks.join(', ')} (${made.frames} frames averaged) appended to ${made.file}; the estimator reloads it`;
}
function updatePicked() {
  const at = new Map((page.state ? page.state.tracks : []).map(([id, x, y, z]) => [id, [x, y, z]]));
  const points = bodyTracks.filter((id) => at.has(id)).map((id) => at.get(id));
  pickedGeometry.setAttribute('position', new THREE.BufferAttribute(new Float32Array(points.flat()), 3));
}
document.getElementById('newbody-clear').addEventListener('click', () => { bodyTracks.length = 0; showBodyTracks(); });
document.getElementById('newbody-create').addEventListener('click', () => {
  if (!socket || socket.readyState !== WebSocket.OPEN) { showResult(newBodyResult, 'rejected', 'not connected'); return; }
  const name = document.getElementById('newbody-name').value.trim();
  const pivot = document.getElementById('newbody-pivot').value;
  const id = nextRequest++;
  pending.set(id, newBodyResult);
  const message = { type: 'body', id, name, tracks: [...bodyTracks], pivot: pivot === '' ? null : Number(pivot) };
  socket.send(JSON.stringify(message));
  page.sent.push({ id, body: name, args: message.tracks, at: Date.now() });
  showResult(newBodyResult, 'sending', `body ${name}`);
});

const formatValue = (value) => (Array.isArray(value) ? value.map((v) => (typeof v === 'number' ? v.toFixed(3).replace(/\.?0+$/, '') : v)).join(', ') : String(value));
function onDetails(message) {
  if (!selected || message.kind !== selected.kind || message.key !== selected.key) return;
  page.details = message.figures;
  const table = details.querySelector('table');
  if (!message.figures) { table.innerHTML = '<tr><td>not live</td><td></td></tr>'; return; }
  const labels = { stamp_ns: 'pose stamp ns', position_m: 'position m', velocity_m_s: 'velocity m/s', speed_m_s: 'speed m/s', sigma_mm: 'σ mm (x, y, z)',
    sigma_position_mm: 'σ position mm', sigma_rotation_deg: 'σ rotation °', orientation_xyzw: 'orientation (x, y, z, w)',
    angular_velocity_rad_s: 'angular velocity rad/s', cameras: 'cameras seeing it', age_s: 'age s', since_update_ms: 'last update ms ago',
    status: 'status', quality: 'quality', grabbing: 'grabbing', joint_angles_deg: 'joint angles ° (base first)', bend_deg: 'bend °',
    tip_m: 'tip m', predicted_tip_m: 'predicted tip m', horizon_ms: 'predicted ms ahead', markers_valid: 'markers valid',
    grabs: 'grabs', releases: 'releases', last_event: 'last event' };
  table.textContent = '';
  for (const [key, label] of Object.entries(labels)) {
    if (!(key in message.figures)) continue;
    const row = table.insertRow();
    row.insertCell().textContent = label;
    row.insertCell().textContent = formatValue(message.figures[key]);
    row.dataset.key = key;
  }
}

// ---------------------------------------------------------------------------------------------
// Recording: every recorder on the bus (its status), start/stop, and the recordings made.
const recorderRows = new Map();
const stamp = () => new Date().toISOString().replace(/[-:]/g, '').replace('T', '_').slice(0, 15);
function updateRecorders(recorders, recordings) {
  const box = document.getElementById('recorders');
  box.querySelector('.none').hidden = recorders.length > 0;
  for (const recorder of recorders) {
    let row = recorderRows.get(recorder.id);
    if (!row) {
      row = document.getElementById('recorder-row').content.firstElementChild.cloneNode(true);
      row.dataset.recorder = recorder.id;
      row.querySelector('.name').textContent = recorder.id;
      const file = row.querySelector('.file');
      file.value = `take_${stamp()}.mcap`;
      row.querySelector('.start').addEventListener('click', () => sendRecorder(row, 'start', file.value.trim()));
      row.querySelector('.stop').addEventListener('click', () => { sendRecorder(row, 'stop'); file.value = `take_${stamp()}.mcap`; });
      box.append(row);
      recorderRows.set(recorder.id, row);
    }
    row.dataset.recording = String(recorder.recording);
    row.querySelector('.light').className = `light ${recorder.error ? 'amber' : recorder.recording ? 'red' : 'green'}`;
    // Samples the recorder's bus dropped on receipt (docs/hostile_input.md), by reason.
    const rejections = Object.entries(recorder.rejections || {});
    const dropped = rejections.length
      ? ` · dropped ${rejections.map(([reason, count]) => `${count} ${reason}`).join(', ')}` : '';
    row.querySelector('.figures').textContent = (recorder.recording
      ? `recording ${recorder.path} · ${recorder.seconds.toFixed(0)} s · ${recorder.topics} topics · ${recorder.messages} messages · ${(recorder.bytes / 1e6).toFixed(2)} MB · ${recorder.messages_per_s.toFixed(0)} msg/s`
      : `idle${recorder.error ? ' · error: ' + recorder.error : ''}`) + dropped;
    row.querySelector('.start').disabled = recorder.recording;
    row.querySelector('.stop').disabled = !recorder.recording;
  }
  const seen = new Set(recorders.map((r) => r.id));
  for (const [id, row] of recorderRows) if (!seen.has(id)) { row.remove(); recorderRows.delete(id); }
  const body = document.querySelector('#recordings tbody');
  const key = `${recordings.length} ${recordings.length ? recordings.at(-1).started_ms : 0}`;
  if (body.dataset.key === key) return;  // the list is capped: its length alone may not change
  body.dataset.key = key;
  body.textContent = '';
  for (const r of [...recordings].reverse()) {
    const row = body.insertRow();
    for (const value of [r.path, r.recorder, r.seconds.toFixed(1), r.messages, (r.bytes / 1e6).toFixed(2)]) row.insertCell().textContent = value;
  }
}

// ---------------------------------------------------------------------------------------------
// Calibration: the steps of docs/calibration.md, run by the console (estimator_node calibrate).
const calibrationResult = { dataset: { recorder: 'calibration' }, querySelector: () => document.getElementById('cal-result') };
function sendCalibration(action, extra = {}) {
  if (!socket || socket.readyState !== WebSocket.OPEN) { showResult(calibrationResult, 'rejected', 'not connected'); return; }
  const id = nextRequest++;
  pending.set(id, calibrationResult);
  socket.send(JSON.stringify({ type: 'calibration', id, action, ...extra }));
  page.sent.push({ id, calibration: action, args: [], at: Date.now() });
  showResult(calibrationResult, 'sending', action);
}
const captureOptions = () => ({ time_service: document.getElementById('cal-time-service').checked });
document.getElementById('cal-capture').addEventListener('click', () => sendCalibration('capture', captureOptions()));
document.getElementById('cal-floor').addEventListener('click', () => sendCalibration('floor_capture', captureOptions()));
for (const button of document.querySelectorAll('.cal-stop')) button.addEventListener('click', () => sendCalibration('stop'));
document.getElementById('cal-solve').addEventListener('click', () => sendCalibration('solve', { wand: document.getElementById('cal-wand').value.trim() }));
document.getElementById('cal-world').addEventListener('click', () => sendCalibration('world', {
  wand: document.getElementById('cal-wand').value.trim(), floor_offset: Number(document.getElementById('cal-floor-offset').value) }));
if (params.get('view') === 'calibration') document.getElementById('calibration').open = true;
// Versions of the estimator's calibration file (panoptes_console --calibration): accept marks an
// automatic change reviewed, revert restores a version's exact file (the estimator reloads it).
document.getElementById('cal-versions').addEventListener('click', (event) => {
  const button = event.target.closest('button[data-version]');
  if (button) sendCalibration(button.dataset.action, { version: Number(button.dataset.version) });
});
let shownVersions = null;
function updateVersions(job) {
  const key = JSON.stringify([job.calibration_file, job.versions]);
  if (key === shownVersions) return;
  shownVersions = key;
  const versions = Array.isArray(job.versions) ? job.versions : [];
  document.getElementById('cal-versions-file').textContent = !job.calibration_file
    ? 'no calibration file: start panoptes_console with --calibration <the estimator\'s calibration.yaml>'
    : job.versions && job.versions.error ? `${job.calibration_file}: ${job.versions.error}`
      : versions.length === 0 ? `${job.calibration_file}: no versions yet (estimator_node calibrate history --start)`
        : `${job.calibration_file}: the last ${versions.length} versions, the newest last`;
  const body = document.querySelector('#cal-versions tbody');
  body.textContent = '';
  const px = (value) => (value === null || value === undefined ? '–' : value.toFixed(2));
  versions.forEach((v, i) => {
    const row = document.createElement('tr');
    row.dataset.version = String(v.version);
    row.dataset.state = v.state;
    for (const text of [`v${v.version}`, v.time_utc, v.state, v.reason, v.cameras.join(', ') || '–',
      `${px(v.residual_before_px)} → ${px(v.residual_after_px)}`]) {
      const cell = document.createElement('td');
      cell.textContent = text;
      row.append(cell);
    }
    const actions = document.createElement('td');
    const button = (action, title) => {
      const b = document.createElement('button');
      b.dataset.action = action;
      b.dataset.version = String(v.version);
      b.textContent = action;
      b.title = title;
      actions.append(b);
    };
    if (v.state === 'applied') button('accept', 'mark this change as reviewed');
    if (i < versions.length - 1) button('revert', `restore v${v.version}'s exact file (a new version; the estimator reloads it)`);
    row.append(actions);
    body.append(row);
  });
}

function drawCoverage(canvas, cells) {
  canvas.width = 96; canvas.height = 72;
  const context = canvas.getContext('2d');
  for (let i = 0; i < 64; ++i) {
    context.fillStyle = cells[i] === '1' ? '#3ec46d' : '#262c35';
    context.fillRect((i % 8) * 12 + 1, Math.floor(i / 8) * 9 + 1, 10, 7);
  }
}

let shownGeneration = null;
function updateCalibration(calibration) {
  page.calibration = calibration;
  const job = calibration.job || {};
  document.getElementById('cal-cameras').textContent = job.cameras_file
    ? `the solve starts from ${job.cameras_file}` : 'no intrinsics file: start panoptes_console with --calibration-cameras <intrinsics.yaml>';
  const coverage = document.getElementById('cal-coverage');
  coverage.textContent = '';
  for (const camera of calibration.cameras) {
    const item = document.createElement('div');
    item.className = 'coverage';
    item.dataset.camera = camera.id;
    item.dataset.percent = String(camera.coverage_percent);
    const canvas = document.createElement('canvas');
    drawCoverage(canvas, camera.cells);
    const text = document.createElement('div');
    text.textContent = `${camera.id}: ${camera.coverage_percent}% · ${camera.frames_with_blobs}/${camera.frames} frames with blobs`;
    item.append(canvas, text);
    coverage.append(item);
  }
  const running = job.result === 'running';
  const status = job.step === 'idle' ? '' : `${job.step}: ${job.result}${running && calibration.capturing ? ` (${calibration.seconds.toFixed(0)} s)` : ''}` +
    (job.result === 'failed' ? ` (exit ${job.exit_code})` : '');
  document.getElementById('cal-log').textContent = status ? `${status}\n${job.log}` : '';
  updateVersions(job);
  // The report and the world frame's summary come once per finished step (they can be large).
  if (job.generation !== shownGeneration) {
    shownGeneration = job.generation;
    fetch('/api/calibration').then((response) => response.json()).then((full) => {
      document.getElementById('cal-world-text').textContent = full.world_text || '';
      showReport(full);
    }).catch(() => { shownGeneration = null; });
  }
}

function showReport(job) {
  const box = document.getElementById('cal-report');
  box.textContent = '';
  const report = job.report;
  if (!report) return;
  const headline = document.createElement('pre');
  headline.textContent = (job.report_text || '').split('\n').slice(0, 3).join('\n');
  box.append(headline);
  const table = document.createElement('table');
  table.innerHTML = '<tr><th>camera</th><th>state</th><th>observations</th><th>raw median px</th><th>raw mean px</th><th>rms px/axis</th><th>max px</th><th>offset ms</th><th>coverage</th></tr>';
  for (const camera of report.cameras) {
    const row = table.insertRow();
    row.dataset.camera = camera.id;
    const raw = camera.raw_frame_error_2d_px.all;
    for (const value of [camera.id, camera.calibrated ? 'calibrated' : `failed: ${camera.failure}`, camera.observations, fixed(raw.median_px, 3),
      fixed(raw.mean_px, 3), fixed(camera.raw_rms_axis_px, 3), fixed(camera.max_px, 2), fixed(camera.time_offset_ms, 3), `${fixed(100 * camera.coverage, 0)}%`])
      row.insertCell().textContent = value;
    if (!camera.calibrated) row.className = 'failed';
  }
  box.append(table);
  const wand = report.wand_length;
  const lengths = document.createElement('div');
  lengths.id = 'cal-wand-length';
  lengths.textContent = wand && wand.samples > 0
    ? `wand length over ${wand.samples} samples: error mean ${fixed(wand.mean_error_mm, 3)} mm, σ ${fixed(wand.sigma_mm, 3)} mm, max ${fixed(wand.max_abs_error_mm, 3)} mm`
    : 'wand length: no samples';
  box.append(lengths);
  for (const name of job.plots) {
    const image = document.createElement('img');
    image.src = `/calibration/${encodeURIComponent(name)}?v=${Date.now()}`;
    image.alt = name; image.title = name;
    box.append(image);
  }
}

function onState(state) {
  page.state = state;
  if (state.full) page.full = state;  // the latest with the slow parts (recorders, calibration, status)
  for (const camera of state.cameras) {
    updateCard(camera);
    updateFrustum(camera);
  }
  markerNames = namesOf(state.subjects || []);
  if (!synthetic) updateTracks(withoutChainMarkers(state.tracks, state.chains || []));
  if (!synthetic) updateSticks(state.subjects || [], state.tracks);
  if (bodyTracks.length) updatePicked();
  updateBodies(state.bodies);
  updateChains(state.chains || []);
  if (state.estimator) {
    const e = state.estimator;
    const element = document.getElementById('estimator');
    // Its status comes every second: silent for 3 s means the estimator is gone (it is picked up
    // again when it comes back).
    element.className = e.age_s > 3 ? 'stale' : (e.cameras_lost ? 'degraded' : '');
    element.textContent = e.age_s > 3 ? `estimator: no status for ${e.age_s.toFixed(0)} s`
      : `estimator: ${e.tracks_confirmed} tracks (+${e.tracks_tentative} tentative) · update p99 ${fixed(e.update_p99_ms, 2)} ms · cpu ${fixed(e.cpu_percent, 0)}%` +
        estimatorCameras(e);
  }
  if (state.recorders) updateRecorders(state.recorders, state.recordings);
  if (state.calibration) updateCalibration(state.calibration);
  if (state.chain_samples) chainSamples = state.chain_samples;
  if (state.console) {
    const c = state.console;
    document.getElementById('console-stats').textContent =
      `console: ${c.clients} client(s) · ${c.snapshots_skipped} skipped · ${c.commands_forwarded} commands sent` +
      counts(' · rejected', c.rejected) + counts(' · bus dropped', c.bus_rejected) +
      (chainSamples.dropped ? ` · chain samples dropped ${chainSamples.dropped} (last: ${chainSamples.last_error})` : '');
  }
}

let chainSamples = {};  // received and dropped rt/panoptes/chains samples (full snapshots)

// Counters by reason as words ("rejected bad_arguments 2, unknown_camera 1"), nothing when none.
function counts(title, counters) {
  const entries = Object.entries(counters || {}).filter(([, n]) => n > 0);
  return entries.length ? `${title} ${entries.map(([reason, n]) => `${reason} ${n}`).join(', ')}` : '';
}

// The point tracks a chain is made of are drawn as the chain: their 6 cm points would hide it.
function withoutChainMarkers(tracks, chainList) {
  const markers = chainList.flatMap((c) => c.markers || []);
  if (!markers.length) return tracks;
  return tracks.filter(([, x, y, z]) => !markers.some(([mx, my, mz]) => Math.hypot(mx - x, my - y, mz - z) < 0.015));
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
// `?fps=N`: at most N renders per second (the default, 0: every animation frame, 60 Hz). Software
// WebGL at 60 Hz takes most of a core; a console beside the cameras on a small machine can draw
// at the snapshot rate (30 Hz) or less. The canvas keeps its last frame (preserveDrawingBuffer).
const maxFps = Math.max(0, Number(params.get('fps')) || 0);
let renderedAt = -Infinity;
function render(now) {
  if (maxFps > 0 && now - renderedAt < 1000 / maxFps - 2) {
    requestAnimationFrame(render);
    return;
  }
  renderedAt = now;
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
  // The bodies this frame shows, for a test that reads the canvas: a snapshot may arrive
  // between this render and the test's look, and the body moves (issue 37).
  page.drawnBodies = page.state ? page.state.bodies : [];
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
