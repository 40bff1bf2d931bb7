// SPDX-License-Identifier: Apache-2.0
// Debian's chromium, headless, through playwright-core, for the console's browser tests: a fresh
// profile, no network beyond the page, the page's console errors collected.
import { chromium } from 'playwright-core';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

export async function openBrowser(viewport) {
  const profile = mkdtempSync(join(tmpdir(), 'panoptes-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: '/usr/bin/chromium',
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
  return { page, errors, close };
}
