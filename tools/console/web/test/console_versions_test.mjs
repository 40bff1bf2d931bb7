// SPDX-License-Identifier: Apache-2.0
// The versions of the estimator's calibration file on the console's calibration page (issue 36
// item 5, docs/console.md "Versions of the calibration"), against tests/integration/
// test_console_versions.sh, in Debian's chromium driven by playwright-core: the page lists the
// versions the shell made, reverts to --revert, accepts the new version, and a version that does not
// exist is refused with the history's reason. Writes the results to --out and a screenshot
// (console_versions.png) to --shots.
//   node console_versions_test.mjs --url <URL> --out <json> --shots <dir> --versions 3 --revert 2
import { join } from 'node:path';
import { parseArgs, runBrowserChecks, sleep, waitFor } from './browser.mjs';

const args = parseArgs(process.argv.slice(2));
const shown = Number(args.versions);
const target = Number(args.revert);
const results = {};

// The rows of the versions table: [version, state, reason].
const rows = (page) => page.evaluate(() => [...document.querySelectorAll('#cal-versions tbody tr')]
  .map((row) => [Number(row.dataset.version), row.dataset.state, row.children[3].textContent]));

// Clicks ACTION on version VERSION's row and waits for the console's final answer.
async function click(page, action, version) {
  const before = await page.evaluate(() => window.panoptes.sent.length);
  await page.click(`#cal-versions tr[data-version="${version}"] button[data-action="${action}"]`);
  const id = await page.evaluate((n) => window.panoptes.sent[n] && window.panoptes.sent[n].id, before);
  return answer(page, id);
}

async function answer(page, id) {
  for (let i = 0; i < 100; i += 1) {
    const found = await page.evaluate((wanted) =>
      window.panoptes.results.find((r) => r.id === wanted && r.result !== 'sent') || null, id);
    if (found) return found;
    await sleep(100);
  }
  return null;
}

await runBrowserChecks({ width: 1400, height: 1000 }, results, args.out, async (page, errors, check) => {
  await page.goto(`${args.url}&view=calibration`);
  const listed = await waitFor(page, (n) => document.querySelectorAll('#cal-versions tbody tr').length === n, shown, 15000);
  results.before = await rows(page);
  check(listed, `the page lists the file's ${shown} versions: ${JSON.stringify(results.before)}`);
  if (!listed) return;
  const last = results.before[results.before.length - 1][0];
  check(await page.locator(`#cal-versions tr[data-version="${last}"] button[data-action="revert"]`).count() === 0,
    'the current version has no revert button');

  const reverted = await click(page, 'revert', target);
  results.revert = reverted;
  check(reverted && reverted.result === 'applied', `revert to v${target}: ${reverted ? reverted.result : 'no answer'}`);
  const added = await waitFor(page, ([n, v]) => {
    const all = [...document.querySelectorAll('#cal-versions tbody tr')];
    return all.length === n + 1 && all[n].children[3].textContent === `revert to ${v}`;
  }, [shown, target], 10000);
  results.after_revert = await rows(page);
  check(added, `a new version "revert to ${target}" is listed last: ${JSON.stringify(results.after_revert)}`);

  const newest = last + 1;
  const accepted = await click(page, 'accept', newest);
  results.accept = accepted;
  check(accepted && accepted.result === 'applied', `accept v${newest}: ${accepted ? accepted.result : 'no answer'}`);
  check(await waitFor(page, (v) => {
    const row = document.querySelector(`#cal-versions tr[data-version="${v}"]`);
    return row && row.dataset.state === 'accepted';
  }, newest, 10000), `v${newest} shown accepted`);
  await page.locator('#cal-versions-box').screenshot({ path: join(args.shots, 'console_versions.png') });

  // A version that does not exist, as a tampered page would send it (a second WebSocket):
  // refused with the history's reason.
  const wsUrl = args.url.replace(/^http/, 'ws').replace(/\/(\?|$)/, '/ws$1');
  const refused = await page.evaluate(async (url) => {
    const socket = new WebSocket(url);
    await new Promise((resolve) => { socket.onopen = resolve; });
    const reply = new Promise((resolve) => {
      socket.onmessage = (event) => { const m = JSON.parse(event.data); if (m.type === 'command_result' && m.id === 900001) resolve(m); };
    });
    socket.send(JSON.stringify({ type: 'calibration', id: 900001, action: 'revert', version: 99 }));
    const answer = await Promise.race([reply, new Promise((resolve) => setTimeout(() => resolve(null), 10000))]);
    socket.close();
    return answer;
  }, wsUrl);
  results.refused = refused;
  check(refused && refused.result === 'rejected' && /no version 99/.test(refused.reason),
    `revert to v99 refused: ${refused ? refused.reason : 'no answer'}`);
  check(errors.length === 0, `no page errors (${errors.join('; ')})`);
});
