// Drives headless Debian chromium over the ember page (called by scripts/test-browser.sh).
//
//   node browser.mjs BASE_URL OUT_DIR CASES_JSON
//
// CASES_JSON: [{ "name", "query", "timeoutS"?, "noDownload"?, "expectError"? }] where
// query is the page's URL parameters. For each case: load the page, wait until it
// reports its passes done, read the canvas (must not be blank), download the linear
// image (PFM) through the page's own button, save a screenshot, and record the page's
// numbers (time per phase included) in OUT_DIR/<name>.json. Exits 1 if the module fails
// to load, a worker errors, the page logs an error or a case times out. A case with
// expectError passes only if the page stops with an error containing that text (an
// injected fault must stop the render, never yield an image).
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const [base, outDir, casesJson] = process.argv.slice(2);
const cases = JSON.parse(casesJson);
fs.mkdirSync(outDir, { recursive: true });
const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'ember-chromium-'));
const problems = [];

const context = await chromium.launchPersistentContext(profile, {
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  headless: true,
  acceptDownloads: true,
  viewport: { width: 1100, height: 900 },
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync'],
});
try {
  for (const c of cases) {
    const page = await context.newPage();
    const log = [];
    const before = problems.length;
    page.on('console', (m) => {
      log.push(`${m.type()}: ${m.text()}`);
      if (m.type() === 'error') problems.push(`${c.name}: console error: ${m.text()}`);
    });
    page.on('pageerror', (e) => problems.push(`${c.name}: page error: ${e.message}`));
    page.on('worker', (w) => w.on('console', (m) => { if (m.type() === 'error') problems.push(`${c.name}: worker console error: ${m.text()}`); }));
    const response = await page.goto(`${base}/index.html?${c.query}&autostart=1`);
    if (!response || !response.ok()) problems.push(`${c.name}: page load HTTP ${response && response.status()}`);
    try {
      await page.waitForFunction(() => window.ember && (window.ember.finished || window.ember.errors.length > 0),
        null, { timeout: (c.timeoutS || 60) * 1000, polling: 100 });
    } catch (e) {
      problems.push(`${c.name}: timed out waiting for the passes (${e.message.split('\n')[0]})`);
    }
    const state = await page.evaluate(() => {
      const e = window.ember;
      const cv = document.getElementById('canvas');
      const px = cv.getContext('2d').getImageData(0, 0, cv.width, cv.height).data;
      let lit = 0, sum = 0;
      for (let i = 0; i < px.length; i += 4) {
        const s = px[i] + px[i + 1] + px[i + 2];
        if (s > 0) lit++;
        sum += s;
      }
      return { loaded: e.loaded, finished: e.finished, errors: e.errors, passes: e.passes, workers: e.workers,
        estimator: e.estimator, elapsedMs: e.elapsedMs, startupMs: e.startupMs, setupMs: e.setupMs, phaseMs: e.phaseMs,
        samples: e.samples, samplesPerSecond: e.samplesPerSecond, rays: e.rays,
        discarded: e.discarded, canvas: { width: cv.width, height: cv.height, litPixels: lit, meanByte: sum / (3 * cv.width * cv.height) } };
    });
    if (c.expectError) {
      // Only the expected error may happen, and it must.
      problems.length = before;
      if (!state.errors.some((e) => e.includes(c.expectError))) {
        problems.push(`${c.name}: expected the page to stop with "${c.expectError}", got ${state.finished ? 'a finished render' : JSON.stringify(state.errors)}`);
      }
      fs.writeFileSync(path.join(outDir, `${c.name}.json`), JSON.stringify({ ...state, log }, null, 2));
      console.log(`${c.name}: stopped with ${JSON.stringify(state.errors)}`);
      await page.close();
      continue;
    }
    for (const err of state.errors) problems.push(`${c.name}: page reported: ${err}`);
    if (!state.loaded) problems.push(`${c.name}: the module did not load`);
    const pixels = state.canvas.width * state.canvas.height;
    if (state.canvas.litPixels < pixels / 10 || state.canvas.meanByte < 1) {
      problems.push(`${c.name}: the canvas is blank (${state.canvas.litPixels} of ${pixels} pixels lit)`);
    }
    if (state.finished && !c.noDownload) {
      const [download] = await Promise.all([page.waitForEvent('download'), page.click('#download')]);
      await download.saveAs(path.join(outDir, `${c.name}.pfm`));
    }
    await page.screenshot({ path: path.join(outDir, `${c.name}.png`) });
    fs.writeFileSync(path.join(outDir, `${c.name}.json`), JSON.stringify({ ...state, log }, null, 2));
    console.log(`${c.name}: ${state.passes} passes, ${state.workers} workers, ${(state.elapsedMs / 1000).toFixed(2)} s (workers ${(state.startupMs / 1000).toFixed(2)} s, setup ${(state.setupMs / 1000).toFixed(2)} s), ` +
      `${Math.round(state.samplesPerSecond)} samples/s, canvas ${state.canvas.litPixels}/${pixels} lit`);
    await page.close();
  }
} finally {
  await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
if (problems.length) {
  console.error(problems.map((p) => `FAIL: ${p}`).join('\n'));
  process.exit(1);
}
