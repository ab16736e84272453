// The viewer in a real browser: Debian's Chromium, driven by playwright-core.
//
//   node test/browser.mjs --overtake BIN --source-dir ROOT --artifacts DIR
//       what CTest runs: records two short drives with BIN (a scenario with incidents and a
//       clean drive), writes their pages with `BIN view FILE --html`, runs a small bench
//       with --record-worst and --html, and opens all of them
//   node test/browser.mjs --page PAGE.html --replay FILE.otr [--expect-incident] [--name NAME]
//                         [--artifacts DIR] [--screenshot-copy PNG]
//       opens a page written by `overtake view FILE --html PAGE.html` for the replay FILE
//   node test/browser.mjs --synthetic --viewer viewer.html [--artifacts DIR]
//       fills the viewer template with replays made by test/encode.mjs (a drive with
//       incidents and a clean one) and opens those
//   node test/browser.mjs --report REPORT.html [--runs N] [--replays N]
//       opens a bench report page (`overtake bench ... --html REPORT.html`); or, with
//       --bench-dir DIR --report-template report.html, fills the template from DIR's
//       bench.json and runs.jsonl (linking every run to a replay page of its own)
//
// Asserts: no console errors and no network requests; the replay's positions (stored as
// differences) agree with the incidents' absolute ones and each path starts at the ego; the
// road and the cars are drawn (pixels differ from the background); after seek(step) the HUD
// speed equals the speed recorded at that step (read from the replay with the page's own
// decoder, here in Node); an incident marker exists when the run has incidents, and clicking
// it seeks there; a truncated copy of the replay shows the warning banner and what could be
// read. Saves a screenshot per page into the artifacts folder.
import { execFileSync, spawn } from 'node:child_process';
import { copyFileSync, existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { basename, dirname, join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

import { chromium } from 'playwright-core';

import { decodeReplay } from '../src/replay.js';
import { syntheticDrive } from './encode.mjs';

const MPH_PER_MPS = 2.2369362920544025;
const CHROMIUM = process.env.OVERTAKE_CHROMIUM || '/usr/bin/chromium';
const ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync'];
const GROUND = [0x1f, 0x2a, 0x1f]; // the scene's background colour (src/viewer/scene.js)

function parseArgs(argv) {
  const a = { pages: [], artifacts: resolve('browser-test-artifacts') };
  let current = null;
  for (let i = 0; i < argv.length; ++i) {
    const k = argv[i];
    const next = () => {
      if (i + 1 >= argv.length) throw new Error(`${k} needs a value`);
      return argv[++i];
    };
    if (k === '--page') a.pages.push((current = { page: resolve(next()), incident: false }));
    else if (k === '--replay') current.replay = resolve(next());
    else if (k === '--expect-incident') current.incident = true;
    else if (k === '--name') current.name = next();
    else if (k === '--synthetic') a.synthetic = true;
    else if (k === '--viewer') a.viewer = resolve(next());
    else if (k === '--artifacts') a.artifacts = resolve(next());
    else if (k === '--screenshot-copy') a.screenshotCopy = resolve(next());
    else if (k === '--report') a.report = resolve(next());
    else if (k === '--report-template') a.reportTemplate = resolve(next());
    else if (k === '--bench-dir') a.benchDir = resolve(next());
    else if (k === '--overtake') a.overtake = resolve(next());
    else if (k === '--source-dir') a.sourceDir = resolve(next());
    else throw new Error(`unknown argument ${k}`);
  }
  return a;
}

// Fills the viewer template as the C++ side does (docs/replay.md).
function fillViewer(template, bytes) {
  return template
    .replace('__OVERTAKE_CONFIG__', () => JSON.stringify({ source: 'embedded' }))
    .replace('__OVERTAKE_DATA__', () => Buffer.from(bytes).toString('base64'));
}

let failures = 0;
let passes = 0;
function check(ok, what) {
  if (ok) {
    passes += 1;
    console.log(`  ok   ${what}`);
  } else {
    failures += 1;
    console.log(`  FAIL ${what}`);
  }
}

/** Collects a page's console errors and warnings, page errors, and requests that leave the disk. */
function watchPage(page, isLocal = (url) => url.startsWith('file:')) {
  const errors = [];
  const requests = [];
  page.on('console', (m) => {
    if (m.type() === 'error' || m.type() === 'warning') errors.push(`console.${m.type()}: ${m.text()}`);
  });
  page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
  page.on('request', (r) => {
    if (!isLocal(r.url()) && !r.url().startsWith('data:')) requests.push(r.url());
  });
  return { errors, requests };
}

async function testPage(context, spec, artifacts) {
  const name = spec.name || basename(spec.page, '.html');
  console.log(`${name}: ${spec.page}`);
  const bytes = readFileSync(spec.replay);
  const replay = decodeReplay(bytes, basename(spec.replay));
  check(replay.problem === null, `the replay decodes in Node without a problem (${replay.problem || replay.summary()})`);
  // Positions are stored as differences (docs/replay.md); an incident record holds the ego's
  // position as is, so it checks the chain of differences the writer coded and this decoder
  // summed. And every path starts near the ego it was coded against.
  let astray = 0;
  for (let k = 0; k < replay.incidents; ++k) {
    const f = replay.incFrame[k];
    if (replay.incX[k] !== replay.egoX[f] || replay.incY[k] !== replay.egoY[f]) astray += 1;
  }
  check(astray === 0, `the ego's summed positions equal the incidents' absolute ones (${replay.incidents} incidents, ${astray} differ)`);
  let farPaths = 0;
  for (let k = 0; k < replay.paths; ++k) {
    const f = replay.pathFrame[k];
    const j = replay.pathStart[k];
    if (replay.pathStart[k + 1] > j && Math.hypot(replay.pathX[j] - replay.egoX[f], replay.pathY[j] - replay.egoY[f]) > 30) farPaths += 1;
  }
  check(farPaths === 0, `every path starts within 30 m of the ego (${replay.paths} paths, ${farPaths} do not)`);

  const page = await context.newPage();
  const { errors, requests } = watchPage(page);
  await page.setViewportSize({ width: 1400, height: 860 });
  const t0 = Date.now();
  await page.goto(pathToFileURL(spec.page).href);
  await page.waitForFunction(() => window.overtakeViewer !== undefined, null, { timeout: 60000 });
  await page.evaluate(() => window.overtakeViewer.ready);
  const loadMs = Date.now() - t0;
  const timing = await page.evaluate(() => window.overtakeViewer.timing);
  console.log(`  timing (ms): ${Object.entries(timing).map(([k, v]) => `${k} ${v.toFixed(0)}`).join(', ')}`);
  const state = await page.getAttribute('#viewer', 'data-state');
  check(state === 'ready', `the page reads the replay (state ${state}; ${loadMs} ms to ready)`);
  const frames = Number(await page.getAttribute('#viewer', 'data-frames'));
  check(frames === replay.frames, `the page has every frame (${frames} of ${replay.frames})`);

  // a step a third of the way in, where the ego is moving
  const probe = replay.step[Math.floor(replay.frames / 3)];
  await page.evaluate((s) => window.overtakeViewer.seek(s), probe);
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
  const pixels = await page.evaluate((ground) => {
    const c = document.getElementById('road');
    const ctx = c.getContext('2d');
    const { width, height } = c;
    const img = ctx.getImageData(0, 0, width, height).data;
    let off = 0;
    let ego = 0;
    let cars = 0;
    let road = 0;
    const near = (k, rgb, tol) => Math.abs(img[k] - rgb[0]) <= tol && Math.abs(img[k + 1] - rgb[1]) <= tol && Math.abs(img[k + 2] - rgb[2]) <= tol;
    for (let k = 0; k < img.length; k += 4) {
      if (!near(k, ground, 2)) off += 1;
      if (near(k, [0x3d, 0xdc, 0x84], 6)) ego += 1;
      if (near(k, [0x6a, 0xa9, 0xff], 6)) cars += 1;
      if (near(k, [0x3a, 0x3e, 0x44], 2)) road += 1;
    }
    return { total: width * height, off, ego, cars, road };
  }, GROUND);
  check(pixels.off / pixels.total > 0.03 && pixels.road / pixels.total > 0.02,
    `the road is drawn (${(100 * pixels.off / pixels.total).toFixed(1)}% of the view differs from the background, ${(100 * pixels.road / pixels.total).toFixed(1)}% is asphalt)`);
  check(pixels.ego > 50, `the ego is drawn (${pixels.ego} pixels of its colour)`);
  check(replay.carStart[replay.frameOfStep(probe) + 1] === replay.carStart[replay.frameOfStep(probe)] || pixels.cars > 50,
    `the other cars are drawn (${pixels.cars} pixels of their colour)`);

  // the HUD shows the recorded speed at several steps
  const picks = [0.1, 0.5, 0.77, 0.999].map((f) => replay.step[Math.floor((replay.frames - 1) * f)]);
  for (const step of picks) {
    const hud = await page.evaluate((s) => {
      window.overtakeViewer.seek(s);
      return { text: document.getElementById('hud-speed').textContent, step: document.getElementById('viewer').dataset.step };
    }, step);
    const want = replay.egoSpeed[replay.frameOfStep(step)] * MPH_PER_MPS;
    check(Number(hud.step) === step && Math.abs(Number(hud.text) - want) < 0.006,
      `after seek(${step}) the HUD speed is ${hud.text} mph (recorded ${want.toFixed(3)})`);
  }

  // incidents: a marker on the timeline, and a click on it seeks there and shows a banner
  const markers = await page.locator('#incident-markers .marker').count();
  if (spec.incident) {
    check(replay.incidents > 0, `the replay records incidents (${replay.incidents})`);
    check(markers > 0, `the timeline marks the incidents (${markers} markers)`);
    if (markers > 0) {
      const first = page.locator('#incident-markers .marker').first();
      const want = Number(await first.getAttribute('data-step'));
      await first.click();
      const now = Number(await page.getAttribute('#viewer', 'data-step'));
      const banners = await page.locator('#incident-banners .banner').count();
      check(now === want && banners > 0, `clicking the first marker seeks to step ${want} (at ${now}) and shows a banner (${banners})`);
      await page.screenshot({ path: join(artifacts, `${name}-incident.png`) });
    }
  } else {
    check(markers === replay.incidents, `no marker without incidents (${markers} markers, ${replay.incidents} incidents)`);
  }

  // a chart click seeks
  const box = await page.locator('#chart-speed .u-over').boundingBox();
  if (box) {
    await page.mouse.click(box.x + box.width * 0.5, box.y + box.height * 0.5);
    const after = Number(await page.getAttribute('#viewer', 'data-step'));
    check(Number.isFinite(after), `a click on the speed chart seeks (step ${after})`);
  }

  // play for a moment at x16: the playhead moves
  const before = Number(await page.getAttribute('#viewer', 'data-step'));
  await page.evaluate((s) => { window.overtakeViewer.seek(s); window.overtakeViewer.setSpeed(16); window.overtakeViewer.play(); }, replay.step[0]);
  await page.waitForTimeout(400);
  await page.evaluate(() => window.overtakeViewer.pause());
  const played = Number(await page.getAttribute('#viewer', 'data-step'));
  check(played > replay.step[0], `playing at x16 moves the playhead (step ${replay.step[0]} to ${played}; was ${before})`);

  // the screenshot: a moment with cars around, zoomed to see them
  await page.evaluate((s) => window.overtakeViewer.seek(s), probe);
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
  const shot = join(artifacts, `${name}.png`);
  await page.screenshot({ path: shot });
  console.log(`  screenshot ${shot}`);

  // a truncated copy: warning banner, and what could be read is shown
  const bodyAt = 16 + bytes.readUInt32LE(12);
  const cut = bytes.subarray(0, bodyAt + Math.floor((bytes.length - bodyAt) * 0.5));
  const partial = await page.evaluate(async (b64) => {
    const bin = atob(b64);
    const u8 = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; ++i) u8[i] = bin.charCodeAt(i);
    await window.overtakeViewer.load(u8, 'cut.otr');
    const banner = document.getElementById('error-banner');
    return { state: document.getElementById('viewer').dataset.state, hidden: banner.hidden, text: banner.textContent, frames: Number(document.getElementById('viewer').dataset.frames) };
  }, Buffer.from(cut).toString('base64'));
  check(partial.state === 'partial' && !partial.hidden && /truncated|ends early|cut short/.test(partial.text) && partial.frames > 0,
    `a truncated replay shows a warning and what it could read (${partial.state}, ${partial.frames} frames: ${partial.text.split('\n')[0]})`);
  // and a file that is not a replay: an error, no exception
  const bad = await page.evaluate(async () => {
    await window.overtakeViewer.load(new TextEncoder().encode('not a replay at all'), 'junk.bin');
    return { state: document.getElementById('viewer').dataset.state, text: document.getElementById('error-banner').textContent };
  });
  check(bad.state === 'error' && /junk\.bin/.test(bad.text), `a file that is not a replay shows an error (${bad.text})`);

  check(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  check(requests.length === 0, `no network requests${requests.length ? `: ${requests.join(', ')}` : ''}`);
  await page.close();
  return { shot, loadMs };
}

// The bench report object (docs/replay.md) from a bench --out folder.
function benchObject(dir) {
  const bench = JSON.parse(readFileSync(join(dir, 'bench.json'), 'utf8'));
  bench.runs = readFileSync(join(dir, 'runs.jsonl'), 'utf8').split('\n').filter(Boolean).map((l) => JSON.parse(l));
  bench.runs.forEach((r, i) => { r.replay = i % 2 === 0 ? `replays/run-${i}.html` : null; });
  return bench;
}

async function testReport(context, path, artifacts, opts = {}) {
  console.log(`report: ${path}`);
  const page = await context.newPage();
  const { errors, requests } = watchPage(page);
  await page.setViewportSize({ width: 1400, height: 1000 });
  await page.goto(pathToFileURL(path).href);
  await page.waitForFunction(() => document.getElementById('report').dataset.state !== 'loading', null, { timeout: 30000 });
  const info = await page.evaluate(() => {
    const rep = window.overtakeReport || { runs: [], rows: [] };
    return {
      state: document.getElementById('report').dataset.state,
      runs: rep.runs.length,
      withReplay: rep.runs.filter((r) => typeof r.replay === 'string' && r.replay).length,
      groups: rep.rows.length,
      summaryRows: document.querySelectorAll('#summary tbody tr').length,
      runRows: document.querySelectorAll('#runs tbody tr').length,
      links: [...document.querySelectorAll('#runs a.replay-link')].map((a) => a.getAttribute('href')),
      charts: document.querySelectorAll('.chart canvas').length,
    };
  });
  check(info.state === 'ready', `the report reads its data (state ${info.state})`);
  check(info.runs > 0 && info.runRows === info.runs, `every run has a row (${info.runRows} of ${info.runs})`);
  check(info.groups > 0 && info.summaryRows === info.groups, `the summary has a row per policy and profile (${info.summaryRows})`);
  check(info.links.length === info.withReplay, `each recorded run links to its replay (${info.links.length} links, ${info.withReplay} replays)`);
  if (opts.linksExist) {
    const missing = info.links.filter((l) => !existsSync(resolve(dirname(path), l)));
    check(info.links.length > 0 && missing.length === 0, `the replay links lead to pages (${info.links.join(', ')}${missing.length ? `; missing ${missing.join(', ')}` : ''})`);
  }
  check(info.charts >= 3, `the charts are drawn (${info.charts} canvases)`);
  check(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  check(requests.length === 0, `no network requests${requests.length ? `: ${requests.join(', ')}` : ''}`);
  const shot = join(artifacts, 'report.png');
  await page.screenshot({ path: shot, fullPage: true });
  console.log(`  screenshot ${shot}`);
  await page.close();
}

// `drive --live` (also recording the run): the page follows the run as it goes, and ends
// with every frame of the recorded file.
async function testLive(context, bin, artifacts) {
  console.log('live: overtake drive --live');
  const otr = join(artifacts, 'live.otr');
  rmSync(otr, { force: true });
  const child = spawn(bin, ['drive', '--live', '--port', '0', '--minutes', '0.1', '--policy', 'reference', '--record', otr, '--quiet'],
    { stdio: ['ignore', 'ignore', 'pipe'] });
  const stop = () => {
    if (child.exitCode === null && child.signalCode === null) child.kill('SIGINT');
  };
  process.on('exit', stop);
  let stderr = '';
  const url = await new Promise((res, rej) => {
    const timer = setTimeout(() => rej(new Error(`drive --live printed no address in 30 s: ${stderr}`)), 30000);
    child.stderr.on('data', (d) => {
      stderr += d;
      const m = stderr.match(/live view at (http:\/\/\S+)/);
      if (m) {
        clearTimeout(timer);
        res(m[1]);
      }
    });
    child.on('exit', (code) => rej(new Error(`drive --live exited (${code}) before serving: ${stderr}`)));
  });
  const page = await context.newPage();
  const { errors, requests: foreign } = watchPage(page, (u) => u.startsWith(url));
  try {
    await page.setViewportSize({ width: 1280, height: 720 });
    await page.goto(url);
    await page.waitForFunction(() => document.getElementById('viewer').dataset.state === 'live', null, { timeout: 30000 });
    await page.waitForFunction(() => Number(document.getElementById('viewer').dataset.frames) > 50, null, { timeout: 30000 });
    const mid = await page.evaluate(() => ({ frames: Number(document.getElementById('viewer').dataset.frames), step: Number(document.getElementById('viewer').dataset.step) }));
    check(mid.frames > 50 && mid.step >= mid.frames - 60, `the page follows the live run (${mid.frames} frames so far, at step ${mid.step})`);
    await page.waitForFunction(() => document.getElementById('viewer').dataset.state !== 'live', null, { timeout: 60000 });
    const end = await page.evaluate(() => ({ state: document.getElementById('viewer').dataset.state, frames: Number(document.getElementById('viewer').dataset.frames) }));
    await page.screenshot({ path: join(artifacts, 'live.png') });
    // the server stays up after the run (until Ctrl-C); the recording is complete once it ends
    let replay = null;
    for (let k = 0; k < 100 && !(replay && replay.ended); ++k) {
      if (k) await new Promise((r) => setTimeout(r, 100));
      try {
        replay = decodeReplay(readFileSync(otr), 'live.otr');
      } catch {
        replay = null;
      }
    }
    check(replay !== null && replay.ended, `drive --live --record wrote a complete replay (${replay ? replay.summary() : 'unreadable'})`);
    if (!replay) return;
    check(end.state === 'ready' && end.frames === replay.frames, `the live page ends with the recorded run (${end.state}, ${end.frames} of ${replay.frames} frames)`);
    const step = replay.step[Math.floor(replay.frames * 0.8)];
    const hud = await page.evaluate((s) => { window.overtakeViewer.seek(s); return document.getElementById('hud-speed').textContent; }, step);
    const want = replay.egoSpeed[replay.frameOfStep(step)] * MPH_PER_MPS;
    check(Math.abs(Number(hud) - want) < 0.006, `after the live run, seek(${step}) shows the recorded speed (${hud} vs ${want.toFixed(3)})`);
    check(errors.length === 0, `no console errors in the live page${errors.length ? `: ${errors.join(' | ')}` : ''}`);
    check(foreign.length === 0, `no requests but to the live server${foreign.length ? `: ${foreign.join(', ')}` : ''}`);
  } finally {
    await page.close();
    stop();
    await new Promise((r) => {
      if (child.exitCode !== null || child.signalCode !== null) return r();
      const t = setTimeout(() => { child.kill('SIGKILL'); r(); }, 5000);
      child.on('exit', () => { clearTimeout(t); r(); });
    });
  }
}

// Starts `bin args...` and resolves to the first http address it prints (stdout or stderr).
function serve(bin, args) {
  const child = spawn(bin, args, { stdio: ['ignore', 'pipe', 'pipe'] });
  const stop = () => {
    if (child.exitCode === null && child.signalCode === null) child.kill('SIGINT');
  };
  process.on('exit', stop);
  let text = '';
  const url = new Promise((res, rej) => {
    const timer = setTimeout(() => rej(new Error(`${basename(bin)} ${args[0]} printed no address in 30 s: ${text}`)), 30000);
    const look = (d) => {
      text += d;
      const m = text.match(/(http:\/\/127\.0\.0\.1:\d+\/\S*)/);
      if (m) {
        clearTimeout(timer);
        res(m[1]);
      }
    };
    child.stdout.on('data', look);
    child.stderr.on('data', look);
    child.on('exit', (code) => rej(new Error(`${basename(bin)} ${args[0]} exited (${code}) before serving: ${text}`)));
  });
  const close = () => new Promise((r) => {
    if (child.exitCode !== null || child.signalCode !== null) return r();
    const t = setTimeout(() => { child.kill('SIGKILL'); r(); }, 5000);
    child.on('exit', () => { clearTimeout(t); r(); });
    stop();
  });
  return { url, close };
}

// `overtake view FILE` (no --html): the page fetches the replay from the server.
async function testServed(context, bin, otr) {
  console.log(`served: overtake view ${basename(otr)}`);
  const server = serve(bin, ['view', otr, '--port', '0']);
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => {
    if (m.type() === 'error' || m.type() === 'warning') errors.push(`console.${m.type()}: ${m.text()}`);
  });
  page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
  try {
    const url = await server.url;
    const foreign = [];
    page.on('request', (r) => {
      if (!r.url().startsWith(url) && !r.url().startsWith('data:')) foreign.push(r.url());
    });
    await page.goto(url);
    await page.evaluate(() => window.overtakeViewer.ready);
    const replay = decodeReplay(readFileSync(otr), basename(otr));
    const got = await page.evaluate(() => ({ state: document.getElementById('viewer').dataset.state, frames: Number(document.getElementById('viewer').dataset.frames) }));
    check(got.state === 'ready' && got.frames === replay.frames, `the served page fetches and reads the replay (${got.state}, ${got.frames} of ${replay.frames} frames)`);
    const step = replay.step[Math.floor(replay.frames / 2)];
    const hud = await page.evaluate((s) => { window.overtakeViewer.seek(s); return document.getElementById('hud-speed').textContent; }, step);
    const want = replay.egoSpeed[replay.frameOfStep(step)] * MPH_PER_MPS;
    check(Math.abs(Number(hud) - want) < 0.006, `served: seek(${step}) shows the recorded speed (${hud} vs ${want.toFixed(3)})`);
    check(errors.length === 0, `no console errors in the served page${errors.length ? `: ${errors.join(' | ')}` : ''}`);
    check(foreign.length === 0, `no requests but to the view server${foreign.length ? `: ${foreign.join(', ')}` : ''}`);
  } finally {
    await page.close();
    await server.close();
  }
}

function run(bin, args) {
  console.log(`$ ${basename(bin)} ${args.join(' ')}`);
  execFileSync(bin, args, { stdio: ['ignore', 'ignore', 'inherit'], timeout: 120000 });
}

// Records the drives and the bench this test opens; returns the pages to test.
function recordWithOvertake(args) {
  const bin = args.overtake;
  const w = args.artifacts;
  if (!args.sourceDir) throw new Error('--overtake needs --source-dir (the source tree, for its scenarios)');
  const drives = [
    { name: 'incident', incident: true,
      flags: ['--scenario', join(args.sourceDir, 'tests/scenarios/hard_brake_ahead.json'), '--policy', 'walkthrough'] },
    { name: 'clean', incident: false, flags: ['--policy', 'reference', '--seed', '1'] },
  ];
  for (const d of drives) {
    const otr = join(w, `${d.name}.otr`);
    const html = join(w, `${d.name}.html`);
    rmSync(otr, { force: true });
    rmSync(html, { force: true });
    run(bin, ['drive', ...d.flags, '--minutes', '0.5', '--record', otr, '--quiet']);
    run(bin, ['view', otr, '--html', html, '--quiet']);
    args.pages.push({ page: html, replay: otr, incident: d.incident, name: d.name });
  }
  const bench = join(w, 'bench');
  rmSync(bench, { recursive: true, force: true });
  run(bin, ['bench', '--policies', 'walkthrough,reference', '--seeds', '1-2', '--minutes', '0.5', '--traffic', 'faithful',
    '--jobs', '1', '--record-worst', '1', '--out', bench, '--html', join(bench, 'report.html'), '--quiet']);
  args.report = join(bench, 'report.html');
  args.reportLinksExist = true;
}

async function main() {
  const args = parseArgs(process.argv.slice(2));
  mkdirSync(args.artifacts, { recursive: true });
  if (args.overtake) recordWithOvertake(args);
  if (args.synthetic) {
    if (!args.viewer) throw new Error('--synthetic needs --viewer viewer.html');
    const template = readFileSync(args.viewer, 'utf8');
    const drives = [
      { name: 'synthetic-incidents', incident: true, drive: syntheticDrive({ seconds: 30, incidents: [{ step: 400, type: 'collision', value: 4 }, { step: 900, type: 'max_jerk', value: 14.2 }] }) },
      { name: 'synthetic-clean', incident: false, drive: syntheticDrive({ seconds: 20 }) },
    ];
    for (const d of drives) {
      const replayPath = join(args.artifacts, `${d.name}.otr`);
      const pagePath = join(args.artifacts, `${d.name}.html`);
      writeFileSync(replayPath, d.drive.bytes);
      writeFileSync(pagePath, fillViewer(template, d.drive.bytes));
      args.pages.push({ page: pagePath, replay: replayPath, incident: d.incident, name: d.name });
    }
  }
  if (args.benchDir) {
    if (!args.reportTemplate) throw new Error('--bench-dir needs --report-template report.html');
    const bench = benchObject(args.benchDir);
    args.report = join(args.artifacts, 'report.html');
    writeFileSync(args.report, readFileSync(args.reportTemplate, 'utf8').replace('__OVERTAKE_BENCH__', () => JSON.stringify(bench).replace(/</g, '\\u003c')));
  }
  if (args.pages.length === 0 && !args.report) throw new Error('nothing to test: give --page PAGE --replay FILE, or --synthetic --viewer viewer.html');
  for (const p of args.pages) if (!p.replay) throw new Error(`--page ${p.page} needs --replay FILE`);

  const profile = mkdtempSync(join(tmpdir(), 'overtake-chromium-'));
  let context;
  try {
    context = await chromium.launchPersistentContext(profile, { executablePath: CHROMIUM, headless: true, args: ARGS });
  } catch (e) {
    rmSync(profile, { recursive: true, force: true });
    throw new Error(`cannot start ${CHROMIUM} (install it with scripts/install-deps.sh): ${e.message.split('\n')[0]}`);
  }
  const shots = [];
  try {
    for (const p of args.pages) shots.push(await testPage(context, p, args.artifacts));
    if (args.report) await testReport(context, args.report, args.artifacts, { linksExist: args.reportLinksExist });
    if (args.overtake) {
      await testServed(context, args.overtake, args.pages[0].replay);
      await testLive(context, args.overtake, args.artifacts);
    }
  } finally {
    await context.close();
    rmSync(profile, { recursive: true, force: true });
  }
  if (args.screenshotCopy && failures === 0 && shots.length) {
    copyFileSync(shots[0].shot, args.screenshotCopy);
    console.log(`copied ${shots[0].shot} to ${args.screenshotCopy}`);
  }
  console.log(`${passes} passed, ${failures} failed`);
  process.exit(failures ? 1 : 0);
}

main().catch((e) => {
  console.error(`browser test: ${e.message}`);
  process.exit(1);
});
