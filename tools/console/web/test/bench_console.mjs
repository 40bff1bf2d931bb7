// SPDX-License-Identifier: Apache-2.0
// Console benchmark (docs/benchmarks.md, issue 18): one chromium page on the console for
// --seconds; prints one JSON line: the chains shown and chain samples received per second, the console's CPU (% of one core, from /proc/<pid>/stat), the
// WebSocket bytes and messages per second it sent (its /api/stats), snapshots skipped, the page's
// 3D frame rate, and the frame rate of a second page showing the 3D view alone (?view=3d) with
// --synthetic-tracks tracks generated in the page, and the page's own milliseconds per frame.
//   node bench_console.mjs --url <console URL> --console-pid <pid> --seconds 10 [--synthetic-tracks 200]
import { readFileSync } from 'node:fs';
import { openBrowser, parseArgs, sleep } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const seconds = Number(args.seconds || 10);
const url = new URL(args.url);
const statsUrl = `${url.protocol}//${url.host}/api/stats?token=${url.searchParams.get('token')}`;
const ticksPerSecond = 100;  // USER_HZ on Linux
const cpuTicks = (pid) => {
  const fields = readFileSync(`/proc/${pid}/stat`, 'utf8').split(') ')[1].split(' ');
  return Number(fields[11]) + Number(fields[12]);  // utime + stime
};

const { context, page, close } = await openBrowser({ width: 1600, height: 1000 });
const out = {};
try {
  await page.goto(args.url);
  await page.waitForFunction(() => window.panoptes.state && window.panoptes.state.cameras.length > 0, null, { timeout: 20000 });
  await sleep(2000);
  const stats0 = await (await fetch(statsUrl)).json();
  const ticks0 = cpuTicks(args['console-pid']);
  const frames0 = await page.evaluate(() => window.panoptes.frames);
  const chainSamples = () => page.evaluate(() => (window.panoptes.full.chain_samples || {}).received || 0);
  const chains0 = await chainSamples();
  const t0 = Date.now();
  await sleep(seconds * 1000);
  const elapsed = (Date.now() - t0) / 1000;
  const stats1 = await (await fetch(statsUrl)).json();
  const ticks1 = cpuTicks(args['console-pid']);
  const frames1 = await page.evaluate(() => window.panoptes.frames);
  const state = await page.evaluate(() => window.panoptes.state);
  out.cameras = state.cameras.length;
  out.blobs_per_snapshot = state.cameras.reduce((sum, c) => sum + c.blobs.length, 0);
  out.tracks = state.tracks.length;
  out.chains = (state.chains || []).length;
  out.chain_samples_per_s = Math.round((await chainSamples() - chains0) / elapsed);  // full snapshots: ~0.5 s stale
  out.seconds = Number(elapsed.toFixed(1));
  out.console_cpu_percent = Number((100 * (ticks1 - ticks0) / ticksPerSecond / elapsed).toFixed(1));
  out.websocket_bytes_per_s = Math.round((stats1.bytes_sent - stats0.bytes_sent) / elapsed);
  out.websocket_messages_per_s = Number(((stats1.messages_sent - stats0.messages_sent) / elapsed).toFixed(1));
  out.snapshots_skipped = stats1.snapshots_skipped - stats0.snapshots_skipped;
  out.page_fps = Number(((frames1 - frames0) / elapsed).toFixed(1));
  await page.close();
  if (args['synthetic-tracks']) {
    const synthetic = await context.newPage();
    await synthetic.goto(`${args.url}&view=3d&synthetic_tracks=${args['synthetic-tracks']}`);
    await sleep(2000);
    const f0 = await synthetic.evaluate(() => window.panoptes.frames);
    const s0 = Date.now();
    await sleep(5000);
    const f1 = await synthetic.evaluate(() => window.panoptes.frames);
    out.synthetic_tracks = Number(args['synthetic-tracks']);
    out.synthetic_fps = Number(((f1 - f0) / ((Date.now() - s0) / 1000)).toFixed(1));
    const timing = await synthetic.evaluate(() => window.panoptes.timing);
    const frames = await synthetic.evaluate(() => window.panoptes.frames);
    out.synthetic_ms_per_frame = Object.fromEntries(Object.entries(timing).map(([k, v]) => [k, Number((v / frames).toFixed(2))]));
  }
} finally {
  await close();
}
console.log(JSON.stringify(out));
