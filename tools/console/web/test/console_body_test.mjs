// SPDX-License-Identifier: Apache-2.0
// A body made from markers in the console's 3D view (docs/console.md, "Bodies from markers"; issue
// 34 item 3), against the live run of tests/integration/test_body_create.sh, in Debian's chromium
// driven by playwright-core: the tracks within --radius of --near are shift+clicked where the page
// draws them, named, and created. Checks that the picks are the tracks clicked, that the console
// answers "applied" with the body's line, that the body then appears in the page's state (the
// estimator reloaded the file), and that the same name again is refused with the CLI's reason.
// Waits for --after-file to exist before creating (the shell's own CLI creation writes the same
// bodies file first). Writes the results to --out and a screenshot (console_body.png) to --shots.
//   node console_body_test.mjs --url <URL> --out <json> --shots <dir> --near x,y,z --radius 0.2
//     --name <body> --after-file <path>
import { existsSync } from 'node:fs';
import { join } from 'node:path';
import { parseArgs, runBrowserChecks, sleep, waitFor } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const near = args.near.split(',').map(Number);
const radius = Number(args.radius || 0.2);
const results = {};

// The confirmed tracks (status 1) within the radius, [id, x, y, z].
const nearTracks = (page) => page.evaluate(([c, r]) => (window.panoptes.state ? window.panoptes.state.tracks : [])
  .filter((t) => t[4] === 1 && Math.hypot(t[1] - c[0], t[2] - c[1], t[3] - c[2]) < r), [near, radius]);

// Where the page draws track `id` now, in the page's CSS pixels (null when it is not drawn).
const screenOf = (page, id) => page.evaluate((wanted) => {
  const track = (window.panoptes.state ? window.panoptes.state.tracks : []).find((t) => t[0] === wanted);
  if (!track) return null;
  const canvas = document.getElementById('view3d');
  const box = canvas.getBoundingClientRect();
  const [u, v] = window.panoptes.project([track[1], track[2], track[3]]);
  return [box.left + u * box.width / canvas.width, box.top + v * box.height / canvas.height];
}, id);

// The console's final answer to request `id` (not "sent").
const answerTo = (page, id) => page.evaluate((wanted) =>
  window.panoptes.results.find((r) => r.id === wanted && r.result !== 'sent') || null, id);

await runBrowserChecks({ width: 1400, height: 900 }, results, args.out, async (page, errors, check) => {
  await page.goto(`${args.url}&view=3d`);
  // Picks the fixture's four confirmed tracks by shift+click; returns [tracks, picked, found].
  const pickFixture = async () => {
    const found = await waitFor(page, ([c, r]) => (window.panoptes.state ? window.panoptes.state.tracks : [])
      .filter((t) => t[4] === 1 && Math.hypot(t[1] - c[0], t[2] - c[1], t[3] - c[2]) < r).length >= 4, [near, radius], 20000);
    const tracks = (await nearTracks(page)).map((t) => t[0]).sort((a, b) => a - b);
    if (tracks.length !== 4) return [tracks, [], found];
    // From 1 m the markers (5-13 cm apart) are 60+ px apart on screen: a click finds its own.
    await page.evaluate(([c]) => window.panoptes.focusOn(c, 1.0), [near]);
    // The view has settled when the fixture stays put on screen (a loaded machine draws late).
    let last = null;
    for (let i = 0; i < 30; i += 1) {
      await sleep(100);
      const now = await page.evaluate(([c]) => window.panoptes.project(c), [near]);
      if (last && Math.hypot(now[0] - last[0], now[1] - last[1]) < 0.5) break;
      last = now;
    }
    // A click the page missed (seen once in the suite: three of four picked) is made again where the
    // track is drawn now, up to five rounds; a click that toggled another pick off is undone the same way.
    const pickedNow = () => page.evaluate(() => [...window.panoptes.bodyTracks].sort((a, b) => a - b));
    await page.keyboard.down('Shift');
    for (let round = 0; round < 5; round += 1) {
      const have = await pickedNow();
      const missing = tracks.filter((id) => !have.includes(id));
      if (missing.length === 0 && have.length === tracks.length) break;
      results.click_rounds += 1;
      for (const id of missing) {
        const at = await screenOf(page, id);
        if (at) await page.mouse.click(at[0], at[1]);
      }
      for (const id of have.filter((id) => !tracks.includes(id))) {
        const at = await screenOf(page, id);
        if (at) await page.mouse.click(at[0], at[1]);
      }
      await sleep(100);
    }
    await page.keyboard.up('Shift');
    return [tracks, await pickedNow(), found];
  };
  results.click_rounds = 0;
  let [tracks, picked, found] = await pickFixture();
  const bodiesBefore = await page.evaluate(() => (window.panoptes.state ? window.panoptes.state.bodies : []).length);
  const shellDoneBefore = existsSync(args['after-file']);
  for (let i = 0; i < 300 && !existsSync(args['after-file']); i += 1) await sleep(100);
  // The shell's creation makes the estimator reload the bodies file; a loaded machine can miss
  // frames then, and tracks that coasted come back under new ids (seen once in a fresh-clone suite:
  // two of the four picked gone, the console's create rejected). The picks are checked against the
  // bus once the reload shows in the page, and made again if any is gone.
  if (!shellDoneBefore) {
    await waitFor(page, (n) => (window.panoptes.state ? window.panoptes.state.bodies : []).length > n, bodiesBefore, 10000);
  }
  await sleep(1000);
  const onBus = (await nearTracks(page)).map((t) => t[0]);
  results.picks_before_reload = picked;
  if (picked.length !== 4 || picked.some((id) => !onBus.includes(id))) {
    await page.click('#newbody-clear');
    [tracks, picked, found] = await pickFixture();
    results.picked_again = true;
  }
  results.tracks = tracks;
  results.picked = picked;
  check(found && tracks.length === 4, `four confirmed tracks near ${near.join(', ')}: ${tracks.join(', ')}`);
  if (tracks.length !== 4) return;
  check(JSON.stringify(picked) === JSON.stringify(tracks), `shift+click picked the tracks clicked (${picked.join(', ')})`);
  check(await page.locator('#newbody').isVisible(), 'the new-body panel shows the picks');
  await page.fill('#newbody-name', args.name);
  const request = await page.evaluate(() => window.panoptes.sent.length);
  const created = Date.now();
  await page.click('#newbody-create');
  const id = await page.evaluate((n) => window.panoptes.sent[n] && window.panoptes.sent[n].id, request);
  let answer = null;
  for (let i = 0; i < 150 && !answer; i += 1) { await sleep(100); answer = await answerTo(page, id); }
  results.answer = answer;
  results.applied_ms = Date.now();  // wall clock, as the shell's date +%s%N after the CLI returned
  const made = await page.evaluate(() => window.panoptes.createdBody || null);
  results.created = made;
  // The same tracks, in any order: a track clicked again in a later round is picked last.
  const sorted = (ids) => JSON.stringify([...ids].sort((a, b) => a - b));
  check(answer && answer.result === 'applied' && made && made.body === args.name &&
    sorted(made.tracks) === sorted(picked),
  `the console made body ${args.name}: ${answer ? answer.result : 'no answer'} (${answer ? answer.reason : ''})`);
  const seen = await waitFor(page, (name) => (window.panoptes.state ? window.panoptes.state.bodies : [])
    .some((b) => b.name === name), args.name, 8000);
  results.body_seen_ms = Date.now() - created;
  check(seen, `body ${args.name} in the page ${results.body_seen_ms} ms after Create was clicked (the estimator reloaded the file)`);
  const text = await page.locator('#newbody .result').textContent();
  check(/^applied: body /.test(text), `the panel says so: "${text}"`);
  if (seen) {
    await sleep(300);
    await page.locator('#view3d-panel').screenshot({ path: join(args.shots, 'console_body.png') });
  }
  // The same name again: the CLI's refusal, shown in the panel.
  const again = await page.evaluate(() => window.panoptes.sent.length);
  await page.click('#newbody-create');
  const againId = await page.evaluate((n) => window.panoptes.sent[n] && window.panoptes.sent[n].id, again);
  let refusal = null;
  for (let i = 0; i < 150 && !refusal; i += 1) { await sleep(100); refusal = await answerTo(page, againId); }
  results.refusal = refusal;
  check(refusal && refusal.result === 'rejected' && /already defined/.test(refusal.reason),
    `the same name again is refused: ${refusal ? refusal.reason : 'no answer'}`);
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
});
