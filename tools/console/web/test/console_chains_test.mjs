// SPDX-License-Identifier: Apache-2.0
// The console's articulated chains in a real browser (Debian's chromium driven by playwright-core),
// against the hand scene replayed live by tests/integration/test_console_chains.sh. Prints
// PASS/FAIL lines and writes the chain states the page received to --out, for the shell to compare
// with the estimator's --out-chains records.
//   node console_chains_test.mjs --url <console URL with token> --out <results.json> --shots <dir>
import { join } from 'node:path';
import { parseArgs, runBrowserChecks, sleep, waitFor } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const results = { samples: [] };

// In one animation frame, right after the page rendered it: the chain the view drew and, around
// where its tip projects, the pixels of the tip's colours (open: green, grabbing: magenta). Their
// centroid is where the page drew the tip.
function tipOnScreen(name) {
  return new Promise((resolve) => requestAnimationFrame(() => {
    const chain = window.panoptes.state.chains.find((c) => c.name === name);
    if (!chain || !chain.tip) { resolve(null); return; }
    const source = document.getElementById('view3d');
    const [u, v] = window.panoptes.project(chain.tip);
    const copy = document.createElement('canvas');
    copy.width = source.width; copy.height = source.height;
    const context = copy.getContext('2d');
    context.drawImage(source, 0, 0);
    const half = 12;
    const x0 = Math.max(0, Math.round(u) - half), y0 = Math.max(0, Math.round(v) - half);
    const pixels = context.getImageData(x0, y0, 2 * half + 1, 2 * half + 1);
    const found = { green: [0, 0, 0], magenta: [0, 0, 0] };
    for (let y = 0; y < pixels.height; ++y) {
      for (let x = 0; x < pixels.width; ++x) {
        const i = 4 * (y * pixels.width + x);
        const [r, g, b] = [pixels.data[i], pixels.data[i + 1], pixels.data[i + 2]];
        const kind = r < 60 && g > 200 && b > 90 && b < 170 ? 'green' : r > 200 && g < 60 && b > 200 ? 'magenta' : null;
        if (kind) { found[kind][0] += 1; found[kind][1] += x0 + x; found[kind][2] += y0 + y; }
      }
    }
    const centroid = ([n, sx, sy]) => (n ? [sx / n + 0.5, sy / n + 0.5] : null);
    resolve({ grabbing: chain.grabbing, u, v, green: found.green[0], magenta: found.magenta[0],
      greenAt: centroid(found.green), magentaAt: centroid(found.magenta) });
  }));
}

await runBrowserChecks({ width: 1400, height: 900 }, results, args.out, async (page, errors, check) => {
  await page.goto(`${args.url}&view=3d`);  // the 3D view alone, as on a wall screen
  const t0 = Date.now();
  const tracking = await waitFor(page, () => window.panoptes.state &&
    (window.panoptes.state.chains || []).some((c) => c.name === 'index' && c.status === 'tracking'), null, 30000);
  check(tracking, `the page receives chain 'index' tracking (${Date.now() - t0} ms after loading)`);
  const listed = await waitFor(page, () => document.querySelector('#chains li[data-chain="index"]') !== null, null, 3000);
  check(listed && !(await page.locator('#chains').isHidden()),
        `the chain is listed beside the 3D view: "${listed ? await page.locator('#chains li[data-chain="index"]').textContent() : ''}"`);

  // Click the list entry: the chain's figures, and the view brought to the finger.
  await page.locator('#chains li[data-chain="index"]').click();
  const details = await waitFor(page, () => window.panoptes.details && window.panoptes.details.kind === 'chain' &&
    window.panoptes.details.name === 'index' && (window.panoptes.details.joint_angles_deg || []).length === 2, null, 4000);
  const figures = await page.evaluate(() => window.panoptes.details);
  const rows = await page.locator('#details tr').count();
  check(details && rows >= 8 && figures.horizon_ms === 80,
        `clicking the entry shows its figures (${rows} rows): ${JSON.stringify(figures)}`);

  // Where the page draws the tip against where the published tip projects in the page's view.
  const offsets = [];
  let open = null;
  for (let i = 0; i < 40 && offsets.length < 10; ++i) {
    const seen = await page.evaluate(tipOnScreen, 'index');
    if (seen && !seen.grabbing && seen.green >= 50) {
      offsets.push([seen.greenAt[0] - seen.u, seen.greenAt[1] - seen.v]);
      open = seen;
    }
    await sleep(100);
  }
  const worst = offsets.length ? Math.max(...offsets.map(([dx, dy]) => Math.hypot(dx, dy))) : Infinity;
  console.log(`tip offsets (dx, dy) px: ${offsets.map(([dx, dy]) => `(${dx.toFixed(2)}, ${dy.toFixed(2)})`).join(' ')}`);
  check(offsets.length >= 5 && worst <= 1.5,
        `the tip drawn where the published tip projects: ${offsets.length} frames, worst ${worst.toFixed(2)} px ` +
        `(${open ? open.green : 0} tip pixels)`);

  // A grab event: the tip and bones turn magenta, the list entry says so, the grab is counted.
  // The chain's entry in the state the page holds now (under load a snapshot without it was seen:
  // reading .grabs of nothing aborted the test).
  await waitFor(page, () => window.panoptes.state.chains?.some((c) => c.name === 'index'), null, 8000);
  const grabsBefore = await page.evaluate(() =>
    window.panoptes.state.chains?.find((c) => c.name === 'index')?.grabs ?? 0);
  const grabbed = await waitFor(page, (before) => {
    const chain = window.panoptes.state.chains.find((c) => c.name === 'index');
    return chain && chain.grabbing && chain.grabs > before;
  }, grabsBefore, 8000);
  let closed = null;
  for (let i = 0; grabbed && i < 20 && !(closed && closed.grabbing); ++i) closed = await page.evaluate(tipOnScreen, 'index');
  const entry = await page.locator('#chains li[data-chain="index"]').getAttribute('class');
  check(grabbed && closed && closed.grabbing && closed.magenta > 20 && closed.green === 0 && entry === 'grabbing' &&
        Math.hypot(closed.magentaAt[0] - closed.u, closed.magentaAt[1] - closed.v) <= 2,
        `on a grab the tip turns from green to magenta (${closed ? closed.magenta : 0} magenta, ${closed ? closed.green : 0} green ` +
        `pixels at the tip; entry class '${entry}')`);
  await page.locator('#view3d-panel').screenshot({ path: join(args.shots, 'console_chains.png') });

  // The chain states the page received, for the shell to find in the estimator's Chain JSONL.
  for (let i = 0; i < 30; ++i) {
    const chain = await page.evaluate(() => window.panoptes.state.chains.find((c) => c.name === 'index'));
    if (chain && chain.status === 'tracking') results.samples.push(chain);
    await sleep(100);
  }
  const stats = await page.evaluate(() => window.panoptes.full.chain_samples);
  results.chain_samples = stats;
  check(stats && stats.received > 100 && stats.dropped === 0,
        `chain samples counted in the full snapshot: ${JSON.stringify(stats)}`);
  check(errors.length === 0, `no console errors in the page (${errors.join(' | ') || 'none'})`);
});
