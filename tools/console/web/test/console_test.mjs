// SPDX-License-Identifier: Apache-2.0
// The operator console in a real browser (Debian's chromium driven by playwright-core), against a
// live simulated system started by tests/integration/test_console.sh. Prints PASS/FAIL lines and
// writes what the page showed (frames and blobs per camera, command times) to --out for the shell
// to check against what each camera published.
//   node console_test.mjs --url <console URL with token> --out <results.json> --shots <dir>
//        --console-pid <pid> --restart <shell command that starts the console again, echoing its pid>
//        --estimator-pid <pid> --estimator-restart <shell command that starts the estimator again>
//        --recorder <id of the idle panoptes_record on the bus> --recording-name <file name to record>
import { spawn } from 'node:child_process';
import http from 'node:http';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { openBrowser, parseArgs, sleep, waitFor } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const results = { samples: [], commands: {}, checks: [] };
let failures = 0;
const pass = (what) => { console.log(`PASS: ${what}`); results.checks.push({ what, ok: true }); };
const fail = (what) => { console.log(`FAIL: ${what}`); results.checks.push({ what, ok: false }); failures += 1; };
const check = (ok, what) => (ok ? pass(what) : fail(what));

const url = new URL(args.url);
const base = `${url.protocol}//${url.host}`;
const token = url.searchParams.get('token');

// --- token: refused without it -----------------------------------------------------------------
for (const [path, what] of [['/', 'page'], ['/api/state', 'state'], ['/app.js', 'script'], [`/?token=${token}x`, 'page with a wrong token']]) {
  // fetch sends no cookie: each of these carries no token or a wrong one.
  const response = await fetch(base + path);
  check(response.status === 401, `${what}: HTTP ${response.status} (401 expected)`);
}

const { context, page, errors: consoleErrors, close } = await openBrowser({ width: 1600, height: 1000 });
try {
  const started = Date.now();
  await page.goto(args.url);

  // --- cameras and blobs ---------------------------------------------------------------------
  const cameras = ['cam0', 'cam1', 'cam2', 'cam3'];
  const allCards = await waitFor(page, (ids) => ids.every((id) => {
    const card = document.querySelector(`.card[data-camera="${id}"]`);
    return card && Number(card.dataset.blobs) > 0;
  }), cameras, 15000);
  check(allCards, `a card with blobs for each of ${cameras.join(', ')} (${Date.now() - started} ms after loading)`);
  // The page's view of each camera (frame number and blobs), sampled for the shell to compare with
  // the cameras' own records; the card's blob count must match what it drew from.
  for (let i = 0; i < 10; ++i) {
    const sample = await page.evaluate(() => window.panoptes.state.cameras.map((camera) => ({
      id: camera.id, frame: camera.frame, blobs: camera.blobs,
      shown: Number(document.querySelector(`.card[data-camera="${camera.id}"]`).dataset.blobs) })));
    results.samples.push(sample);
    await sleep(100);
  }
  check(results.samples.every((sample) => sample.every((camera) => camera.shown === camera.blobs.length)),
        'each card shows the blob count of the frame it drew');
  // The estimator's predicted windows (for each camera's next frame) drawn on every card, most of
  // them around a blob of the frame shown (a garbage window would hold none).
  const withWindows = await waitFor(page, (n) => window.panoptes.state.cameras.length === n &&
    window.panoptes.state.cameras.every((c) => (c.windows || []).length > 0), cameras.length, 10000);
  const windowStats = await page.evaluate(() => window.panoptes.state.cameras.map((c) => [
    (c.windows || []).filter(([x, y, hw, hh]) => c.blobs.some(([bx, by]) => Math.abs(bx - x) <= hw + 3 && Math.abs(by - y) <= hh + 3)).length,
    (c.windows || []).length]));
  const held = windowStats.reduce((sum, [inside]) => sum + inside, 0);
  const windowsShown = windowStats.reduce((sum, [, all]) => sum + all, 0);
  check(withWindows && held >= 0.25 * windowsShown,
        `predicted windows on every camera: ${held} of ${windowsShown} around a blob of the frame shown`);
  const health = await page.evaluate(() => window.panoptes.state.cameras.map((c) => `${c.id} ${c.health.light} (${c.health.reason})`));
  check(health.every((light) => !light.includes(' red ')), `health lights: ${health.join(', ')}`);
  // The estimator's calibration health on each card (issue 36: a per-camera light with the reason);
  // no camera of this unbumped scene is quarantined.
  const calibrated = await waitFor(page, () => [...document.querySelectorAll('.card .figures')].length > 0 &&
    [...document.querySelectorAll('.card .figures')].every((f) => /calibration \S+ (ok|small bias|unknown)/.test(f.textContent)),
  null, 8000);
  const calibrationTexts = await page.evaluate(() => [...document.querySelectorAll('.card')].map((card) =>
    `${card.dataset.camera}: ${(card.querySelector('.figures').textContent.match(/calibration [^·]*/) || ['none'])[0].trim()}`));
  check(calibrated, `calibration lights on every card: ${calibrationTexts.join(', ')}`);

  // --- 3D view ------------------------------------------------------------------------------
  const ready3d = await waitFor(page, () => window.panoptes.state && window.panoptes.state.bodies.length > 0 &&
                                window.panoptes.state.tracks.length > 0, null, 10000);
  check(ready3d, '3D view has tracks and bodies');
  // One task reads the canvas and places each body with the page's fixed view: pixels of the
  // body's axes (pure red, green or blue; grid, tracks and frusta have other colours) must lie
  // within 8 px of where its position projects.
  const { litPixels, bodies } = await page.evaluate(() => {
    const source = document.getElementById('view3d');
    const copy = document.createElement('canvas');
    copy.width = source.width; copy.height = source.height;
    const context2d = copy.getContext('2d');
    context2d.drawImage(source, 0, 0);
    const pixels = context2d.getImageData(0, 0, copy.width, copy.height).data;
    const isLit = (i) => pixels[i] + pixels[i + 1] + pixels[i + 2] > 60;
    const isAxis = (i) => {
      const [r, g, b] = [pixels[i], pixels[i + 1], pixels[i + 2]];
      return (r > 150 && g < 90 && b < 90) || (g > 150 && r < 90 && b < 90) || (b > 150 && r < 90 && g < 90);
    };
    let lit = 0;
    for (let i = 0; i < pixels.length; i += 4) if (isLit(i)) lit += 1;
    // The poses the canvas was drawn from, not the newest snapshot (they can differ by a frame).
    const near = (window.panoptes.drawnBodies || []).map((body) => {
      const [u, v] = window.panoptes.project(body.pose.p);
      let count = 0;
      for (let y = Math.round(v) - 8; y <= Math.round(v) + 8; ++y) {
        for (let x = Math.round(u) - 8; x <= Math.round(u) + 8; ++x) {
          if (x >= 0 && y >= 0 && x < copy.width && y < copy.height && isAxis(4 * (y * copy.width + x))) count += 1;
        }
      }
      return { name: body.name, u: Math.round(u), v: Math.round(v), lit: count };
    });
    return { litPixels: lit / (pixels.length / 4), bodies: near };
  });
  check(bodies.length > 0 && bodies.every((b) => b.lit >= 3),
        `each body drawn where its pose projects: ${bodies.map((b) => `${b.name} at (${b.u}, ${b.v}) ${b.lit} axis px`).join(', ')}`);
  check(litPixels > 0.002, `3D canvas is not blank (${(100 * litPixels).toFixed(2)}% of pixels lit)`);
  check(consoleErrors.length === 0, `page loaded with no console errors (${consoleErrors.join(' | ') || 'none'})`);
  // three.js (1.27 MB) comes gzipped to a browser that accepts it (issue 32).
  const three = await page.evaluate(() => {
    const entry = performance.getEntriesByType('resource').find((e) => e.name.includes('/vendor/three.module.js'));
    return entry ? { encoded: entry.encodedBodySize, decoded: entry.decodedBodySize } : null;
  });
  check(three && three.decoded > 1e6 && three.encoded < 0.4 * three.decoded,
        `three.module.js sent compressed: ${three ? `${three.encoded} bytes for ${three.decoded}` : 'not loaded'}`);
  // Every figure on a card explains itself, and the legend lists them all.
  const explained = await page.evaluate(() => ({
    untitled: [...document.querySelectorAll('.card .figures span')].filter((span) => !span.title).length,
    spans: document.querySelectorAll('.card .figures span').length,
    legend: document.querySelectorAll('#legend dd').length }));
  check(explained.spans >= 28 && explained.untitled === 0 && explained.legend >= 8,
        `card figures explained: ${explained.spans} with a tooltip (${explained.untitled} without), ${explained.legend} in the legend`);
  await page.screenshot({ path: join(args.shots, 'console_overview.png') });
  await page.locator('#view3d-panel').screenshot({ path: join(args.shots, 'console_3d.png') });

  // --- threshold to maximum and back -----------------------------------------------------------
  const card0 = page.locator('.card[data-camera="cam0"]');
  // Times are taken in the page when it sends a command and when it sees the change (one machine,
  // one wall clock): a slow CDP round trip on a loaded machine does not count against the console.
  const sentAt = (command, first) => page.evaluate(([c, a]) =>
    window.panoptes.sent.filter((s) => s.command === c && (a === null || String(s.args[0]) === a)).at(-1).at, [command, first]);
  // Clicks `button` and returns when the page sent `command` for it. Read at once, the newest send
  // may still be an earlier one under load: cam2's clear was stamped with cam1's, 8.6 s before the
  // polygon it cleared, and the cameras' records were judged over an empty window (stop 95).
  const clickAndSentAt = async (button, command) => {
    const count = () => page.evaluate((c) => window.panoptes.sent.filter((s) => s.command === c).length, command);
    const before = await count();
    await button.click();
    await waitFor(page, ([c, n]) => window.panoptes.sent.filter((s) => s.command === c).length > n, [command, before], 5000);
    return (await count()) > before ? sentAt(command, null) : null;
  };
  const blobsOf = (camera, condition) => waitFor(page, ([id, zero]) => {
    const n = Number(document.querySelector(`.card[data-camera="${id}"]`).dataset.blobs);
    if (zero ? n !== 0 : n === 0) return false;
    window.panoptes.seenAt = Date.now();
    return true;
  }, [camera, condition === 'none'], 3000);
  await card0.locator('input.threshold').fill('255');
  results.commands.threshold_max_ms = await sentAt('set_threshold', '255');
  const gone = await blobsOf('cam0', 'none');
  const goneMs = gone ? await page.evaluate(() => window.panoptes.seenAt) - results.commands.threshold_max_ms : Infinity;
  // Quiet: 50-60 ms. Under a parallel build on both cores (issue 37's loaded run) 1034 ms was seen;
  // the bound is what a loaded 2-core machine keeps, the figure goes into the results.
  check(goneMs < 2500, `threshold 255: cam0's blobs gone in the page ${goneMs} ms after the command was sent`);
  const applied = await waitFor(page, () => document.querySelector('.card[data-camera="cam0"] .result').classList.contains('applied'), null, 12000);
  check(applied, `the card shows the camera's acknowledgement: "${await card0.locator('.result').textContent()}"`);
  await card0.screenshot({ path: join(args.shots, 'console_threshold.png') });
  // A second tab opened now shows the camera's threshold, not the slider's default (issue 32).
  const tab = await context.newPage();
  await tab.goto(args.url);
  const tabShows = await waitFor(tab, () => {
    const input = document.querySelector('.card[data-camera="cam0"] input.threshold');
    return input && input.value === '255' && input.nextElementSibling.textContent === '255';
  }, null, 15000);  // a new tab loads three.js and connects: seconds under a parallel build
  check(tabShows, `a new tab's cam0 threshold slider shows the camera's 255: ${await tab.evaluate(() =>
    document.querySelector('.card[data-camera="cam0"] input.threshold')?.value)}`);
  await tab.close();
  await sleep(Math.max(0, results.commands.threshold_max_ms + 1500 - Date.now()));  // 1.5 s at the maximum
  await card0.locator('input.threshold').fill('64');
  results.commands.threshold_restore_ms = await sentAt('set_threshold', '64');
  const back = await blobsOf('cam0', 'some');
  const backMs = back ? await page.evaluate(() => window.panoptes.seenAt) - results.commands.threshold_restore_ms : Infinity;
  check(backMs < 1000, `threshold 64: cam0's blobs back in the page ${backMs} ms after the command was sent`);

  // --- a preview on request: camera_node's image under the blobs --------------------------------
  // A second request when the first brings no image within 6 s: in one fresh-clone suite run
  // (stop 58, beside the accuracy grid and the formatting check) cam0 never logged the first
  // request; a page or camera that never answers still fails both. Whether the page sent each
  // request is printed.
  let previewShown = false;
  for (let attempt = 0; attempt < 2 && !previewShown; ++attempt) {
    await card0.locator('button.preview').click();
    previewShown = await waitFor(page, () => {
      const card = document.querySelector('.card[data-camera="cam0"]');
      return card.dataset.previewShown !== undefined && card.dataset.previewShown === card.dataset.previewStamp;
    }, null, attempt === 0 ? 6000 : 10000);
    const sent = await page.evaluate(() => window.panoptes.sent.filter((s) => s.command === 'preview').length);
    if (!previewShown) console.log(`preview attempt ${attempt + 1}: no image within the wait (${sent} preview request(s) sent by the page)`);
  }
  const previewImage = await page.evaluate(async () => {
    const bytes = new Uint8Array(await (await fetch('/api/preview/cam0')).arrayBuffer());
    const header = new TextDecoder().decode(bytes.slice(0, 20)).split(/\s+/);
    let bright = 0;
    for (let i = 15; i < bytes.length; ++i) bright += bytes[i] > 128 ? 1 : 0;
    return { magic: header[0], width: Number(header[1]), height: Number(header[2]), bright };
  });
  check(previewShown && previewImage.magic === 'P5' && previewImage.width === 640 && previewImage.bright > 0,
        `preview on request drawn under cam0's blobs (${previewImage.width}x${previewImage.height} P5, ${previewImage.bright} bright pixels)`);

  // --- mask: drag a rectangle over the left half of cam1's image ------------------------------
  // The drag starts where cam1's canvas is at that moment: the pointer is put there, and the page's
  // own hit test (elementFromPoint) must name the canvas before the button goes down, or the canvas
  // is measured again (a card re-wrapping its text moves it; stop 77's check: both gestures sent
  // nothing). Up to three gestures; each failed one says what was under the pointer, whether the
  // mask mode was on and whether the page was connected. A page that never sends the mask still
  // fails all three.
  const card1 = page.locator('.card[data-camera="cam1"]');
  let maskArgs = null;
  let attempts = 0;
  while (!maskArgs && attempts < 3) {
    attempts += 1;
    // The button toggles the mask mode: press it only while it is off.
    if (await card1.locator('button.mask.active').count() === 0) await card1.locator('button.mask').click();
    let box = null;
    let onCanvas = false;
    for (let aim = 0; aim < 10 && !onCanvas; ++aim) {
      await sleep(aim === 0 ? 200 : 100);  // the mask mode's layout settled before the canvas is measured
      box = await card1.locator('canvas').boundingBox();
      await page.mouse.move(box.x + 4, box.y + 4);
      onCanvas = await page.evaluate(([x, y]) => document.elementFromPoint(x, y) ===
        document.querySelector('.card[data-camera="cam1"] canvas'), [box.x + 4, box.y + 4]);
    }
    const before = await page.evaluate(() => ({
      active: document.querySelector('.card[data-camera="cam1"] button.mask').classList.contains('active'),
      connected: window.panoptes.connected,
    }));
    await page.mouse.down();
    await page.mouse.move(box.x + box.width * 0.4, box.y + box.height * 0.6, { steps: 5 });
    await page.mouse.move(box.x + box.width / 2, box.y + box.height - 1, { steps: 5 });
    const dragging = await page.evaluate(() => Boolean(document.querySelector('.card[data-camera="cam1"]').drag));
    await card1.screenshot({ path: join(args.shots, 'console_mask.png') });
    await page.mouse.up();
    maskArgs = await waitFor(page, () => window.panoptes.results.some((r) => r.command === 'add_mask'), null, 5000)
      ? await page.evaluate(() => window.panoptes.results.find((r) => r.command === 'add_mask').args) : null;
    if (!maskArgs) {
      console.log(`mask gesture ${attempts}: no add_mask result within 5 s (pointer on the canvas: ${onCanvas}, ` +
        `mask mode on: ${before.active}, drag followed by the page: ${dragging}, connected: ${before.connected}, ` +
        `card says "${await card1.locator('.result').textContent()}")`);
    }
  }
  results.commands.mask_attempts = attempts;
  results.commands.mask_args = maskArgs;
  if (maskArgs) results.commands.mask_ms = await sentAt('add_mask', null);
  // Which half failed, when one did: the page never sent the command, or no result came back.
  const maskSent = await page.evaluate(() => window.panoptes.sent.filter((s) => s.command === 'add_mask').length);
  check(maskArgs && maskArgs[0] === 'rect',
        `mask sent as add_mask ${maskArgs ? maskArgs.join(' ') : '(none)'} (gesture ${attempts} of at most 3; ${maskSent} sent by the page)`);
  await sleep(600);
  // The page has centroids only: a spot on the mask's edge keeps its outside pixels and its
  // centroid may lie a pixel or two inside; count those deeper than 3 px.
  let inside = 0;
  for (let i = 0; i < 10 && maskArgs; ++i) {
    inside += await page.evaluate((mask) => {
      const camera = window.panoptes.state.cameras.find((c) => c.id === 'cam1');
      const [, x, y, w, h] = mask.map(Number);
      return camera.blobs.filter(([bx, by]) => bx >= x + 3 && bx < x + w - 3 && by >= y + 3 && by < y + h - 3).length;
    }, maskArgs);
    await sleep(50);
  }
  if (maskArgs) check(inside === 0, `no blob of cam1 inside the mask in the page (${inside} seen over 0.5 s)`);
  // The cameras' records are judged from 1 s after the command to the clear: leave them >= 0.8 s.
  if (results.commands.mask_ms) await sleep(Math.max(0, results.commands.mask_ms + 1800 - Date.now()));
  results.commands.clear_masks_ms = await clickAndSentAt(card1.locator('button.clear_masks'), 'clear_masks');

  // --- polygon mask: click three corners on cam2, then the first again ---------------------------
  const card2p = page.locator('.card[data-camera="cam2"]');
  // Drawn again if no acknowledgement came (a click lost while the card re-rendered, seen once in a
  // loaded CI run; twice in a row in a loaded fresh-clone run, stop 95); the camera's log shows one
  // add_mask poly either way. The triangle is placed around cam2's blobs, so it waits for some.
  let polyArgs = null;
  for (let attempt = 0; attempt < 3 && !polyArgs; ++attempt) {
    if (await card2p.locator('button.polygon.active').count()) await card2p.locator('button.polygon').click();  // reset
    await card2p.locator('button.polygon').click();
    await waitFor(page, () => window.panoptes.state.cameras.find((c) => c.id === 'cam2').blobs.length > 0, null, 2000);
    const box2 = await card2p.locator('canvas').boundingBox();
    // A triangle around where cam2 sees blobs now (so that it had blobs to remove): its top edge on
    // the blobs' top, its sides through their box's bottom corners, in image pixels.
    const corners = await page.evaluate(() => {
      const camera = window.panoptes.state.cameras.find((c) => c.id === 'cam2');
      const canvas = document.querySelector('.card[data-camera="cam2"] canvas');  // sized as the image
      const [width, height] = [canvas.width, canvas.height];
      // No blob at this instant: a triangle about the image's centre (its corners would be NaN).
      const blobs = camera.blobs.length ? camera.blobs : [[width / 2, height / 3]];
      const xs = blobs.map((b) => b[0]), ys = blobs.map((b) => b[1]);
      const x0 = Math.min(...xs) - 30, x1 = Math.max(...xs) + 30, y0 = Math.min(...ys) - 30, y1 = Math.max(...ys) + 30;
      const cx = (x0 + x1) / 2, w = x1 - x0, h = y1 - y0;
      const clamp = (v, high) => Math.max(1, Math.min(high - 2, v));
      return [[clamp(cx - w, width), clamp(y0, height)], [clamp(cx + w, width), clamp(y0, height)], [clamp(cx, width), clamp(y1 + h, height)]]
        .map(([x, y]) => [x / width, y / height]);
    });
    for (const [fx, fy] of corners) await page.mouse.click(box2.x + box2.width * fx, box2.y + box2.height * fy);
    await page.mouse.move(box2.x + box2.width * 0.5, box2.y + box2.height * 0.5);
    await card2p.screenshot({ path: join(args.shots, 'console_polygon.png') });
    await page.mouse.click(box2.x + box2.width * corners[0][0] + 2, box2.y + box2.height * corners[0][1] + 2);
    polyArgs = await waitFor(page, () => window.panoptes.results.some((r) => r.command === 'add_mask' && r.args[0] === 'poly'), null, 5000)
      ? await page.evaluate(() => window.panoptes.results.find((r) => r.command === 'add_mask' && r.args[0] === 'poly').args) : null;
    if (!polyArgs) {
      // Which half failed: the page never sent the command (clicks lost), or no result came back.
      const state = await page.evaluate(() => ({
        sent: window.panoptes.sent.filter((s) => s.command === 'add_mask' && s.args[0] === 'poly').length,
        blobs: window.panoptes.state.cameras.find((c) => c.id === 'cam2').blobs.length,
        connected: window.panoptes.connected,
      }));
      console.log(`polygon attempt ${attempt + 1}: no acknowledgement within 5 s (add_mask poly sent by the page: ` +
        `${state.sent}, polygon mode on: ${await card2p.locator('button.polygon.active').count() > 0}, cam2 blobs: ` +
        `${state.blobs}, corners ${JSON.stringify(corners.map(([x, y]) => [x.toFixed(3), y.toFixed(3)]))}, ` +
        `connected: ${state.connected}, card says "${await card2p.locator('.result').textContent()}")`);
    }
  }
  results.commands.polygon_args = polyArgs;
  check(polyArgs && polyArgs.length === 7, `polygon sent as add_mask ${polyArgs ? polyArgs.join(' ') : '(none)'}`);
  if (polyArgs) results.commands.polygon_ms = await page.evaluate(() =>
    window.panoptes.sent.filter((s) => s.command === 'add_mask' && s.args[0] === 'poly').at(-1).at);
  await sleep(600);
  let insidePolygon = 0;
  for (let i = 0; polyArgs && i < 10; ++i) {
    insidePolygon += await page.evaluate((poly) => {
      const p = poly.slice(1).map(Number);
      const corners = [[p[0], p[1]], [p[2], p[3]], [p[4], p[5]]];
      // Deeper than 3 px inside every edge of the (convex) triangle.
      const inside = (x, y) => corners.every(([ax, ay], k) => {
        const [bx, by] = corners[(k + 1) % 3], [cx, cy] = corners[(k + 2) % 3];
        const side = (bx - ax) * (y - ay) - (by - ay) * (x - ax), other = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
        return side * Math.sign(other) / Math.hypot(bx - ax, by - ay) > 3;
      });
      return window.panoptes.state.cameras.find((c) => c.id === 'cam2').blobs.filter(([x, y]) => inside(x, y)).length;
    }, polyArgs);
    await sleep(50);
  }
  check(polyArgs && insidePolygon === 0, `no blob of cam2 inside the polygon in the page (${insidePolygon} seen over 0.5 s)`);
  if (results.commands.polygon_ms) await sleep(Math.max(0, results.commands.polygon_ms + 1800 - Date.now()));
  results.commands.clear_polygon_ms = await clickAndSentAt(card2p.locator('button.clear_masks'), 'clear_masks');

  // --- click a body, then a track, in the 3D view: their figures -------------------------------
  const canvasBox = await page.locator('#view3d').boundingBox();
  const clickWorld = async (point) => {
    const [u, v, width, height] = await page.evaluate((p) => [...window.panoptes.project(p),
      document.getElementById('view3d').width, document.getElementById('view3d').height], point);
    await page.mouse.click(canvasBox.x + u * canvasBox.width / width, canvasBox.y + v * canvasBox.height / height);
  };
  // The body moves while the click travels: under load the pose the click aimed at can be a few
  // hundred ms old when the page handles it, and the body 15 px away. A missed click selects
  // nothing (or a track); the test aims again at the body's newest pose, three times at most.
  const body = await page.evaluate(() => window.panoptes.state.bodies[0]);
  let bodyShown = false;
  const bodyAttempts = [];
  for (let attempt = 0; attempt < 3 && !bodyShown; ++attempt) {
    const pose = await page.evaluate((name) => (window.panoptes.state.bodies.find((b) => b.name === name) || {}).pose, body.name);
    if (!pose) break;
    await clickWorld(pose.p);
    const selectedBody = await waitFor(page, (name) => window.panoptes.selected && window.panoptes.selected.kind === 'body' &&
      window.panoptes.selected.key === name, body.name, 1000);
    bodyShown = selectedBody && await waitFor(page, (name) => window.panoptes.details && window.panoptes.details.kind === 'body' &&
      window.panoptes.details.name === name && !document.getElementById('details').hidden, body.name, 5000);
    bodyAttempts.push(selectedBody ? (bodyShown ? 'shown' : 'selected, no figures within 5 s')
      : `selected ${JSON.stringify(await page.evaluate(() => window.panoptes.selected))}`);
  }
  // The figures are compared with the pose the estimator published at the stamp the page shows
  // (test_console.sh, its --out-poses record), never with whichever pose is streamed when the test
  // looks: the body moves, and under load the two can be a few hundred ms apart.
  const bodyFigures = await page.evaluate(() => ({ figures: window.panoptes.details,
    rows: document.querySelectorAll('#details tr').length,
    stampRow: (document.querySelector('#details tr[data-key="stamp_ns"] td:last-child') || {}).textContent }));
  const shownStamp = bodyShown ? bodyFigures.figures.stamp_ns : 0;
  results.body_details = bodyShown ? { name: body.name, stamp_ns: shownStamp, position_m: bodyFigures.figures.position_m } : null;
  check(bodyShown && shownStamp > 0 && bodyFigures.stampRow === String(shownStamp) && bodyFigures.rows >= 9 &&
        bodyFigures.figures.sigma_position_mm.every((v) => v >= 0),
        `clicking body ${body.name} shows its figures (${bodyFigures.rows} rows, pose stamp ${shownStamp}; clicks: ${bodyAttempts.join('; ')})`);
  await page.locator('#view3d-panel').screenshot({ path: join(args.shots, 'console_details.png') });
  // The loose track farthest on screen from every body (the body's markers are tracks too).
  const track = await page.evaluate(() => {
    const state = window.panoptes.state;
    const bodyPixels = state.bodies.map((b) => window.panoptes.project(b.pose.p));
    let best = null;
    for (const [id, x, y, z] of state.tracks) {
      const [u, v] = window.panoptes.project([x, y, z]);
      const clearance = Math.min(...bodyPixels.map(([bu, bv]) => Math.hypot(bu - u, bv - v)));
      if (!best || clearance > best.clearance) best = { id, p: [x, y, z], clearance };
    }
    return best;
  });
  // Aimed, as the body above, at the track's newest position, three times at most: a loaded run
  // (stop 71's loaded check, the test at 60 s) missed it once with a single click at the position
  // read before, and the body's figures stayed.
  let trackShown = false;
  const trackAttempts = [];
  for (let attempt = 0; track && attempt < 3 && !trackShown; ++attempt) {
    const p = await page.evaluate((id) => {
      const found = window.panoptes.state.tracks.find((t) => t[0] === id);
      return found ? found.slice(1, 4) : null;
    }, track.id);
    if (!p) { trackAttempts.push('gone'); break; }
    await clickWorld(p);
    trackShown = await waitFor(page, () => window.panoptes.details && window.panoptes.details.kind === 'track', null, 3000);
    trackAttempts.push(trackShown ? 'shown' : `selected ${JSON.stringify(await page.evaluate(() => window.panoptes.selected))}`);
  }
  const trackFigures = await page.evaluate(() => window.panoptes.details);
  // Tracks close together on screen: the nearest to the click is shown, which may be a neighbour.
  check(trackShown && trackFigures.cameras >= 2 && trackFigures.sigma_mm.length === 3 && trackFigures.age_s >= 0,
        `clicking near track ${track ? track.id : '(none)'} shows track ${trackFigures && trackFigures.id}'s figures (clicks: ${trackAttempts.join('; ')}): ${JSON.stringify(trackFigures)}`);
  await page.locator('#details .close').click();

  // --- recording: start, stop, listed --------------------------------------------------------
  if (args.recorder) {
    const row = page.locator(`.recorder[data-recorder="${args.recorder}"]`);
    const listed = await waitFor(page, (id) => document.querySelector(`.recorder[data-recorder="${id}"]`), args.recorder, 8000);
    check(listed, `recorder ${args.recorder} listed in the page`);
    await row.locator('input.file').fill(args['recording-name']);
    await row.locator('button.start').click();
    const recording = await waitFor(page, (id) => document.querySelector(`.recorder[data-recorder="${id}"]`).dataset.recording === 'true',
                                    args.recorder, 5000);
    const started = await waitFor(page, (id) => document.querySelector(`.recorder[data-recorder="${id}"] .result`).classList.contains('applied'),
                                  args.recorder, 5000);
    check(recording && started, `recording started from the page: "${await row.locator('.result').textContent()}"`);
    await sleep(1500);
    await row.locator('button.stop').click();
    const inList = await waitFor(page, (name) => [...document.querySelectorAll('#recordings td:first-child')].some((cell) => cell.textContent.endsWith(name)),
                                 args['recording-name'], 6000);
    const entry = await page.evaluate((name) => window.panoptes.full.recordings.find((r) => r.path.endsWith(name)), args['recording-name']);
    results.recording = entry || null;
    await page.locator('#recording').screenshot({ path: join(args.shots, 'console_recording.png') });
    check(inList && entry && entry.messages > 0, `the stopped recording is listed: ${JSON.stringify(entry)}`);
  }

  // --- a command the camera rejects: its reason is shown ---------------------------------------
  const card2 = page.locator('.card[data-camera="cam2"]');
  await card2.locator('input.gain').fill('6');
  const rejected = await waitFor(page, () => document.querySelector('.card[data-camera="cam2"] .result').classList.contains('rejected'), null, 6000);
  check(rejected, `a gain the simulated camera lacks is shown rejected: "${await card2.locator('.result').textContent()}"`);
  // The slider goes back to what the camera reports once the user leaves it (3 s). That wait, and
  // the page's 3 s before it marks a killed estimator stale (below), run while the bad input is sent:
  // the three checks touch different things (cam2's slider, cam0/cam3's commands, the estimator).
  await card2.locator('input.gain').blur();
  const gainBackWait = waitFor(page, () => document.querySelector('.card[data-camera="cam2"] input.gain').value === '0', null, 8000);
  let staleWait = null;
  if (args['estimator-pid']) {
    process.kill(Number(args['estimator-pid']), 'SIGKILL');
    staleWait = waitFor(page, () => document.getElementById('estimator').classList.contains('stale') &&
      window.panoptes.state.tracks.length === 0, null, 8000);
  }

  // --- bad input over a second WebSocket -----------------------------------------------------
  const bad = await page.evaluate(async (wsUrl) => {
    const replies = [];
    const socket = new WebSocket(wsUrl);
    await new Promise((resolve) => { socket.onopen = resolve; });
    socket.onmessage = (event) => { const m = JSON.parse(event.data); if (m.type === 'command_result') replies.push(m); };
    socket.send('this is not JSON');
    socket.send(JSON.stringify({ type: 'command', id: 1, camera: 'cam0', command: 'set_threshold', args: ['x'.repeat(20000)] }));
    socket.send(JSON.stringify({ type: 'command', id: 2, camera: 'cam0', command: 'format_disk' }));
    socket.send(JSON.stringify({ type: 'command', id: 3, camera: 'cam0', command: 'set_threshold', args: [70000] }));
    socket.send(JSON.stringify({ type: 'command', id: 4, camera: 'nocam', command: 'set_threshold', args: [10] }));
    socket.send(JSON.stringify({ type: 'command', id: 5, camera: 'cam3', command: 'add_mask', args: ['rect', 600, 400, 100, 100] }));
    for (let i = 0; i < 40; ++i) socket.send(JSON.stringify({ type: 'command', id: 100 + i, camera: 'cam3', command: 'set_threshold', args: [0] }));
    // Every one of the 46 messages is answered (sent, or rejected with its reason): wait for the 46
    // answers, not a fixed time. 800 ms once passed with none (issue 37: the console's process beside
    // the heaviest unit tests), and closing the socket then dropped the messages not yet read.
    for (const end = Date.now() + 15000; replies.length < 46 && Date.now() < end;)
      await new Promise((resolve) => setTimeout(resolve, 50));
    socket.close();
    return replies;
  }, `${base.replace('http', 'ws')}/ws?token=${token}`);
  const reason = (counter) => bad.filter((r) => r.counter === counter).length;
  check(reason('bad_message') === 1, `malformed message rejected (${reason('bad_message')})`);
  check(reason('oversized') === 1, `oversized message rejected (${reason('oversized')})`);
  check(reason('unknown_command') === 1, `unknown command rejected (${reason('unknown_command')})`);
  check(reason('out_of_range') === 2, `out-of-range threshold and a mask outside the image rejected (${reason('out_of_range')})`);
  check(reason('unknown_camera') === 1, `unknown camera rejected (${reason('unknown_camera')})`);
  const sent = bad.filter((r) => r.result === 'sent').length;
  check(reason('rate_limited') >= 15 && sent <= 25, `command flood rate-limited (${sent} sent, ${reason('rate_limited')} refused)`);
  results.commands.flood_sent = sent;
  // The page's own cookie would carry the token: the refusal is checked with a bare handshake.
  const refusedStatus = await new Promise((resolve) => {
    const request = http.request({ host: url.hostname, port: url.port, path: '/ws', headers: {
      Connection: 'Upgrade', Upgrade: 'websocket', 'Sec-WebSocket-Version': '13',
      'Sec-WebSocket-Key': 'cGFub3B0ZXMtY29uc29sZQ==' } });
    request.on('upgrade', () => resolve(101));
    request.on('response', (response) => resolve(response.statusCode));
    request.on('error', () => resolve(0));
    request.end();
  });
  check(refusedStatus === 401, `WebSocket handshake without the token: HTTP ${refusedStatus} (401 expected)`);
  // The rejections counted in the header are words on one line that never hides the connection badge.
  const header = await waitFor(page, () => document.getElementById('console-stats').textContent.includes('rejected'), null, 4000) &&
    await page.evaluate(() => {
      const stats = document.getElementById('console-stats').textContent;
      const badge = document.getElementById('connection').getBoundingClientRect();
      const bar = document.querySelector('header').getBoundingClientRect();
      return { stats, json: /[{}"]/.test(stats), height: bar.height, badgeVisible: badge.width > 0 && badge.bottom <= bar.bottom };
    });
  check(header && !header.json && header.height < 40 && header.badgeVisible,
        `header after rejections: one line (${header && header.height} px), no JSON: "${header && header.stats}"`);

  const gainBack = await gainBackWait;
  check(gainBack, `the rejected gain's slider shows the camera's gain again: ${await card2.locator('input.gain').inputValue()}`);

  // --- the estimator killed (above) and started again: the page shows it gone, then its tracks again
  if (staleWait) {
    const stale = await staleWait;
    check(stale, `the page shows the estimator gone: "${await page.locator('#estimator').textContent()}"`);
    const t0 = Date.now();
    spawn('bash', ['-c', args['estimator-restart']], { stdio: 'ignore' }).unref();
    const back = await waitFor(page, () => !document.getElementById('estimator').classList.contains('stale') &&
      window.panoptes.state.tracks.length > 0 && window.panoptes.state.bodies.length > 0, null, 20000);
    check(back, `tracks and bodies back in the page after the estimator's restart, without a reload (${Date.now() - t0} ms)`);
  }

  // --- the console killed and started again: the page recovers without a reload ----------------
  const connectsBefore = await page.evaluate(() => window.panoptes.connects);
  process.kill(Number(args['console-pid']), 'SIGKILL');
  const down = await waitFor(page, () => !window.panoptes.connected, null, 3000);
  check(down, 'the page notices the console is gone');
  const restarted = spawn('bash', ['-c', args.restart], { stdio: ['ignore', 'pipe', 'inherit'] });
  let newPid = '';
  restarted.stdout.on('data', (data) => { newPid += data; });
  await new Promise((resolve) => restarted.on('exit', resolve));
  results.restarted_pid = Number(newPid.trim());
  const t0 = Date.now();
  const recovered = await waitFor(page, (before) => window.panoptes.connected && window.panoptes.connects > before &&
    window.panoptes.state.cameras.length === 4 && window.panoptes.state.cameras.every((c) => c.frame > 0),
  connectsBefore, 15000);
  check(recovered, `the page reconnected without a reload (${Date.now() - t0} ms after the restart)`);
  const frames0 = await page.evaluate(() => window.panoptes.state.cameras.map((c) => c.frame));
  const streaming = await waitFor(page, (before) => window.panoptes.state.cameras.every((c, i) => c.frame > before[i]),
                                  frames0, 12000);  // the new participant's discovery, on a loaded machine
  check(streaming, 'blobs keep streaming after the restart (every camera\'s frame number advances)');
  await page.screenshot({ path: join(args.shots, 'console_after_restart.png') });
  check(consoleErrors.filter((e) => !e.includes('WebSocket')).length === 0,
        `no console errors in the page (${consoleErrors.length ? consoleErrors.join(' | ') : 'none'})`);
  results.console_errors = consoleErrors;
} catch (error) {
  fail(`browser test aborted: ${error.stack || error}`);
} finally {
  await close();
  writeFileSync(args.out, JSON.stringify(results, null, 1));
}
process.exit(failures === 0 ? 0 : 1);
