// SPDX-License-Identifier: Apache-2.0
// Debian's chromium, headless, through playwright-core, for the console's browser tests: a fresh
// profile, no network beyond the page, the page's console errors collected.
import { chromium } from 'playwright-core';
import { mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

export async function openBrowser(viewport) {
  const profile = mkdtempSync(join(tmpdir(), 'panoptes-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    // /usr/bin/chromium, unable to raise its own priority above the processes it watches.
    executablePath: fileURLToPath(new URL('./chromium.sh', import.meta.url)),
    headless: true,
    viewport,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync'],
  });
  const page = context.pages()[0] || await context.newPage();
  const errors = [];
  page.on('console', (message) => { if (message.type() === 'error') errors.push(message.text()); });
  page.on('pageerror', (error) => errors.push(String(error)));
  const close = async () => { await context.close(); rmSync(profile, { recursive: true, force: true }); };
  return { context, page, errors, close };
}

// `--name value` pairs of the command line as an object.
export function parseArgs(argv) {
  return Object.fromEntries(argv.reduce((pairs, value, i, all) =>
    (i % 2 === 0 ? [...pairs, [value.replace(/^--/, ''), all[i + 1]]] : pairs), []));
}

export const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));

// True when `predicate` holds in the page within `timeoutMs`.
export async function waitFor(page, predicate, arg, timeoutMs) {
  try {
    await page.waitForFunction(predicate, arg, { timeout: timeoutMs, polling: 20 });
    return true;
  } catch {
    return false;
  }
}

// Runs `body(page, errors, check)` in a fresh browser: each check prints PASS/FAIL and goes into
// `results.checks`; an exception is one more failure. Writes `results` to `out` and exits 1 if any
// check failed.
export async function runBrowserChecks(viewport, results, out, body) {
  let failures = 0;
  results.checks = [];
  const check = (ok, what) => {
    console.log(`${ok ? 'PASS' : 'FAIL'}: ${what}`);
    results.checks.push({ what, ok });
    if (!ok) failures += 1;
  };
  const { page, errors, close } = await openBrowser(viewport);
  try {
    await body(page, errors, check);
  } catch (error) {
    check(false, `browser test aborted: ${error.stack || error}`);
  } finally {
    await close();
    writeFileSync(out, JSON.stringify(results, null, 1));
  }
  process.exit(failures === 0 ? 0 : 1);
}
