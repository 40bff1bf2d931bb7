// SPDX-License-Identifier: Apache-2.0
// Marker names and the marker set's sticks in the console's 3D view (docs/marker_sets.md, "Labels
// on the wire"; docs/console.md), against the live labelling run of
// tests/integration/test_live_labels.sh, in Debian's chromium driven by playwright-core. Checks
// that the page receives the subject with its names and sticks, that each named track is drawn with
// its name, and that the sticks are drawn (their light blue in the view). Writes the names the page
// showed to --out for the shell to compare with the estimator's own --out-labels, and a
// screenshot of the view (console_labels.png) to --shots. With --ready-file, writes that file once
// the page has loaded: the shell starts the walk then (a browser started beside eight cameras took
// 6-13 s to load the page, and missed most of the walk).
//   node console_labels_test.mjs --url <console URL with token> --out <results.json> --shots <dir> [--ready-file F]
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { parseArgs, runBrowserChecks, sleep } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const results = { names: [] };

// Pixels of the sticks' colour (0x9ad1ff; the frusta's 0x6fa8dc is not counted) in the 3D view,
// counted right after a render.
function stickPixels() {
  return new Promise((resolve) => requestAnimationFrame(() => {
    const source = document.getElementById('view3d');
    const copy = document.createElement('canvas');
    copy.width = source.width; copy.height = source.height;
    const context = copy.getContext('2d');
    context.drawImage(source, 0, 0);
    const pixels = context.getImageData(0, 0, copy.width, copy.height).data;
    let n = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      if (Math.abs(pixels[i] - 154) < 12 && Math.abs(pixels[i + 1] - 209) < 12 && pixels[i + 2] > 240) n += 1;
    }
    resolve(n);
  }));
}

await runBrowserChecks({ width: 1400, height: 900 }, results, args.out, async (page, errors, check) => {
  await page.goto(`${args.url}&view=3d`);
  if (args['ready-file']) writeFileSync(args['ready-file'], `${Date.now()}\n`);
  const t0 = Date.now();
  // One loop while the walk lasts: under load a page saw the names only 9 s after loading, and
  // checks made one after the other found the walk over (no track, no stick, no label). Each pass,
  // once the subject's names and sticks are in: a moment of labels (five in all) and the sticks'
  // pixels until they are seen.
  let ready = false, readyMs = 0, blue = 0, tracks = 0, moments = 0, drawn = 0, wrong = 0, shot = false;
  while (Date.now() - t0 < 25000 && !shot) {
    if (!ready) {
      ready = await page.evaluate(() => {
        const s = window.panoptes.state && (window.panoptes.state.subjects || []).find((x) => x.name === 's1');
        return Boolean(s && Object.keys(s.names || {}).length >= 30 && window.panoptes.sticksDrawn >= 20);
      });
      readyMs = Date.now() - t0;
      if (!ready) { await sleep(100); continue; }
    }
    // A moment: every named track that is drawn carries its name as its label.
    if (moments < 5) {
      const seen = await page.evaluate(() => new Promise((resolve) => requestAnimationFrame(() => {
        const subjects = window.panoptes.state.subjects || [];
        const s = subjects.find((x) => x.name === 's1') || { names: {} };
        const out = [];
        for (const [id, trail] of window.panoptes.trackLabels || new Map()) {
          const name = s.names[String(id)];
          // With several subjects a label is "<subject>:<name>" (as C3D exports name them).
          const shown = subjects.length > 1 ? trail.label.userData.label.text.replace(/^s1:/, '') : trail.label.userData.label.text;
          if (name) out.push([id, name, shown]);
        }
        resolve(out);
      })));
      if (seen.length) moments += 1;
      for (const [id, name, text] of seen) {
        drawn += 1;
        if (text !== name) wrong += 1;
        results.names.push([id, name]);
      }
    }
    if (blue <= 300) {
      // The subject from 3.2 m: its named markers' centroid (state.tracks: [id, x, y, z]).
      tracks = await page.evaluate(() => {
        const s = (window.panoptes.state.subjects || []).find((x) => x.name === 's1');
        const named = window.panoptes.state.tracks.filter(([id]) => s && s.names[String(id)]);
        if (!named.length) return 0;
        const c = [1, 2, 3].map((k) => named.reduce((sum, t) => sum + t[k], 0) / named.length);
        window.panoptes.focusOn(c, 3.2);
        return named.length;
      });
      await sleep(150);
      blue = await page.evaluate(stickPixels);
    }
    // The picture last: a screenshot took seconds on a loaded machine.
    if (blue > 300 && moments >= 5) {
      await page.locator('#view3d-panel').screenshot({ path: join(args.shots, 'console_labels.png') });
      shot = true;
    }
    await sleep(100);
  }
  const subject = await page.evaluate(() => (window.panoptes.state.subjects || []).find((x) => x.name === 's1') || {});
  check(ready, `the page receives subject s1 with ${Object.keys(subject.names || {}).length} names and ` +
    `${(subject.sticks || []).length} sticks, draws ${await page.evaluate(() => window.panoptes.sticksDrawn)} ` +
    `(${readyMs} ms after loading)`);
  check(blue > 300, `the sticks are drawn (${blue} pixels of their light blue in the view; ${tracks} named tracks)`);
  // At least one moment's worth of a subject's names (a loaded page may draw new frames only now
  // and then: a fresh clone's suite saw 41 over the 5 moments), and never a wrong one.
  check(drawn >= 30 && wrong === 0,
    `named tracks drawn with their names: ${drawn - wrong} of ${drawn} over ${moments} moments`);
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
});
