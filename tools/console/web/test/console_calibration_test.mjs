// SPDX-License-Identifier: Apache-2.0
// The console's calibration page in a real browser (Debian's chromium driven by playwright-core),
// started by tests/integration/test_console_calibration.sh: capture the wand with live coverage,
// stop, solve, and the report shown. Writes what the page showed to --out.
//   node console_calibration_test.mjs --url <console URL with token> --out <results.json> --shots <dir>
//        --cameras <shell command that runs the cameras (waving the wand) and returns when they end>
//        --floor-cameras <the same, the wand laid on the floor> --wand <spec>
import { spawn } from 'node:child_process';
import { writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { openBrowser, parseArgs, waitFor } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const results = { checks: [] };
let failures = 0;
const check = (ok, what) => {
  console.log(`${ok ? 'PASS' : 'FAIL'}: ${what}`);
  results.checks.push({ what, ok });
  if (!ok) failures += 1;
};
const job = (page) => page.evaluate(() => (window.panoptes.calibration || {}).job || {});

const { page, errors, close } = await openBrowser({ width: 1600, height: 1200 });
try {
  await page.goto(args.url);
  check(await waitFor(page, () => window.panoptes.connected && window.panoptes.calibration, null, 10000), 'the calibration page is connected');
  // A solve before any capture is refused with the step to do first.
  await page.fill('#cal-wand', args.wand);
  await page.click('#cal-solve');
  check(await waitFor(page, () => document.getElementById('cal-result').textContent.includes('capture the wand first'), null, 5000),
        `solve before a capture refused: "${await page.textContent('#cal-result')}"`);

  await page.check('#cal-time-service');
  await page.click('#cal-capture');
  check(await waitFor(page, () => window.panoptes.calibration.job.step === 'capture' && window.panoptes.calibration.job.result === 'running',
                      null, 5000), 'capture running');
  const cameras = spawn('bash', ['-c', args.cameras], { stdio: 'ignore' });
  const camerasDone = new Promise((resolve) => cameras.on('exit', resolve));
  const live = await waitFor(page, () => window.panoptes.calibration.cameras.length === 6 &&
    window.panoptes.calibration.cameras.every((c) => c.coverage_percent > 0), null, 15000);
  check(live, 'live 8x8 coverage for all six cameras while capturing');
  await Promise.race([camerasDone, new Promise((resolve) => setTimeout(resolve, 20000))]);
  await page.locator('#calibration').screenshot({ path: join(args.shots, 'console_calibration_capture.png') });
  await page.locator('.cal-stop').first().click();
  check(await waitFor(page, () => ['done', 'stopped'].includes(window.panoptes.calibration.job.result) &&
    window.panoptes.calibration.job.have_wand && !window.panoptes.calibration.capturing, null, 10000),
  `capture stopped: ${JSON.stringify((await job(page)).result)}`);
  await new Promise((resolve) => setTimeout(resolve, 700));  // the next full state
  results.coverage = Object.fromEntries(await page.evaluate(() => window.panoptes.calibration.cameras.map((c) =>
    [c.id, [c.coverage_percent, c.frames, c.frames_with_blobs]])));

  await page.click('#cal-solve');
  const solved = await waitFor(page, () => window.panoptes.calibration.job.step === 'solve' && window.panoptes.calibration.job.result !== 'running' &&
    document.querySelectorAll('#cal-report tr[data-camera]').length > 0, null, 30000);
  const solve = await job(page);
  check(solved && solve.result === 'done', `solve ran from the page: ${solve.result} (exit ${solve.exit_code})`);
  results.report_rows = await page.evaluate(() => [...document.querySelectorAll('#cal-report tr[data-camera]')].map((row) => ({
    camera: row.dataset.camera, state: row.cells[1].textContent, observations: row.cells[2].textContent, median: row.cells[3].textContent })));
  check(results.report_rows.length === 6 && results.report_rows.every((row) => row.state === 'calibrated'),
        `report table: ${results.report_rows.map((r) => `${r.camera} ${r.state} ${r.median} px`).join(', ')}`);
  const wandLine = await page.textContent('#cal-wand-length');
  check(/error mean .* mm, σ .* mm/.test(wandLine), `wand-length statistics shown: "${wandLine}"`);
  const plots = await waitFor(page, () => {
    const images = [...document.querySelectorAll('#cal-report img')];
    return images.length >= 3 && images.every((image) => image.complete && image.naturalWidth > 0);
  }, null, 10000);
  check(plots, `the solve's plots load in the page (${await page.locator('#cal-report img').count()} images)`);
  await page.locator('#calibration').screenshot({ path: join(args.shots, 'console_calibration_report.png') });
  // A world frame without a floor capture is refused with the step to do first.
  await page.click('#cal-world');
  check(await waitFor(page, () => document.getElementById('cal-result').textContent.includes('floor first'), null, 5000),
        `world frame before a floor capture refused: "${await page.textContent('#cal-result')}"`);

  // Step 4c: the wand laid on the floor, then the world frame.
  await page.click('#cal-floor');
  check(await waitFor(page, () => window.panoptes.calibration.job.step === 'floor_capture' && window.panoptes.calibration.job.result === 'running',
                      null, 5000), 'floor capture running');
  const floorCameras = spawn('bash', ['-c', args['floor-cameras']], { stdio: 'ignore' });
  await Promise.race([new Promise((resolve) => floorCameras.on('exit', resolve)), new Promise((resolve) => setTimeout(resolve, 25000))]);
  await page.locator('.cal-stop').last().click();
  check(await waitFor(page, () => window.panoptes.calibration.job.result === 'done' && window.panoptes.calibration.job.have_floor, null, 10000),
        `floor capture stopped: ${JSON.stringify((await job(page)).result)}`);
  await page.fill('#cal-floor-offset', '0.007');
  await page.click('#cal-world');
  const world = await waitFor(page, () => window.panoptes.calibration.job.step === 'world' && window.panoptes.calibration.job.result !== 'running' &&
    document.getElementById('cal-world-text').textContent.length > 0, null, 30000);
  const worldJob = await job(page);
  results.world_text = await page.textContent('#cal-world-text');
  check(world && worldJob.result === 'done' && results.world_text.includes('placements'),
        `world frame set from the page: ${worldJob.result}: "${results.world_text.split('\n')[0]}"`);
  await page.locator('#calibration .steps > li').nth(3).screenshot({ path: join(args.shots, 'console_calibration_world.png') });
  check(errors.length === 0, `no console errors in the page (${errors.join(' | ') || 'none'})`);
} catch (error) {
  check(false, `browser test aborted: ${error.stack || error}`);
} finally {
  await close();
  writeFileSync(args.out, JSON.stringify(results, null, 1));
}
process.exit(failures === 0 ? 0 : 1);
