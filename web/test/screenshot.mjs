// A screenshot of a viewer page at one step, for the README:
//   node test/screenshot.mjs PAGE.html STEP OUT.png [WIDTH HEIGHT]
// docs/images/viewer.png: `overtake drive --minutes 30 --seed 3 --record r.otr`,
// `overtake view r.otr --html r.html`, then this at step 58150 (a lane change in a curve).
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

import { chromium } from 'playwright-core';

const [pagePath, step, out, width = '1400', height = '800'] = process.argv.slice(2);
if (!pagePath || step === undefined || !out) {
  console.error('usage: node test/screenshot.mjs PAGE.html STEP OUT.png [WIDTH HEIGHT]');
  process.exit(2);
}
const profile = mkdtempSync(join(tmpdir(), 'overtake-chromium-'));
const context = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.OVERTAKE_CHROMIUM || '/usr/bin/chromium',
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
    '--disable-background-networking', '--disable-component-update', '--disable-sync'],
});
try {
  const page = await context.newPage();
  await page.setViewportSize({ width: Number(width), height: Number(height) });
  await page.goto(pathToFileURL(resolve(pagePath)).href);
  await page.evaluate(() => window.overtakeViewer.ready);
  await page.evaluate((s) => window.overtakeViewer.seek(s), Number(step));
  await page.waitForTimeout(300); // the charts move their window a moment later
  await page.screenshot({ path: resolve(out) });
  console.log(`wrote ${resolve(out)}`);
} finally {
  await context.close();
  rmSync(profile, { recursive: true, force: true });
}
