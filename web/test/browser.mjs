// The viewer in a real browser: Debian's Chromium, driven by playwright-core.
//
//   node test/browser.mjs --overtake BIN --source-dir ROOT --artifacts DIR [--viewer viewer.html]
//       what CTest runs: records two short drives with BIN (a scenario with incidents and a
//       clean drive) and a scenario cut from a third (`BIN cut`, then driven), writes their
//       pages with `BIN view FILE --html` (or, with --viewer, fills that template itself: a
//       page built from this tree against a binary built before it), runs a small bench
//       with --record-worst and --html, and opens all of them
//   node test/browser.mjs --page PAGE.html --replay FILE.otr [--expect-incident]
//                         [--expect-collision TEXT] [--name NAME] [--artifacts DIR]
//                         [--screenshot-copy PNG]
//       opens a page written by `overtake view FILE --html PAGE.html` for the replay FILE
//   node test/browser.mjs --synthetic --viewer viewer.html [--artifacts DIR]
//       fills the viewer template with replays made by test/encode.mjs (a drive with
//       incidents, a clean one, one as an older writer wrote it, and a cut scenario's with
//       checkpoint records, frames from a later step and the replay's name in the config)
//       and opens those
//   node test/browser.mjs --report REPORT.html [--runs N] [--replays N]
//       opens a bench report page (`overtake bench ... --html REPORT.html`); or, with
//       --bench-dir DIR --report-template report.html, fills the template from DIR's
//       bench.json, runs.jsonl and summary.json (linking every run to a replay page of its own)
//
// Asserts: no console errors and no network requests; the replay's positions (stored as
// differences) agree with the incidents' absolute ones and each path starts at the ego; the
// road and the cars are drawn (pixels differ from the background); after seek(step) the HUD
// speed equals the speed recorded at that step (read from the replay with the page's own
// decoder, here in Node); an incident marker exists when the run has incidents, and clicking
// it seeks there; a collision's marker and banner name its kind and fault; the near-miss
// chart shows every TTC and headway the replay holds, the HUD the TTC at a step, the status
// line the report's collisions and near misses; a truncated copy of the replay shows the
// warning banner and what could be read. The cut control shows the `overtake cut` command for
// the current time (it follows seeks and playback, the traffic choice, and copies or selects
// the command); a cut scenario's replay says where it was cut from and marks the moment on
// the timeline, and its clock (from a later step than 0) drives the time label, the slider
// and the charts. Each contact is marked once (its latched repeats lighter), its marker and
// banner name it. The bench report shows the intervals, error bars, row notes, precision,
// speed against safety and paired comparisons (matrices with their mirror cells) its data
// holds, with no two chart labels overlapping, and so do copies of it with the data of
// today's bench filled in, with nine policies, as a bench from before contacts, with an older
// bench's data, and with no summary. Saves a screenshot per page into the artifacts folder.
import { execFileSync, spawn } from 'node:child_process';
import { copyFileSync, existsSync, mkdirSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { basename, dirname, join, resolve } from 'node:path';
import { pathToFileURL } from 'node:url';

import { chromium } from 'playwright-core';

import { decodeReplay } from '../src/replay.js';
import { overlapping } from '../src/report/layout.js';
import { PAIR_FIGURES, signed } from '../src/report/tables.js';
import { clock, cutCommand, cutOriginText, incidentText, latchedText, safetyStatusText } from '../src/viewer/format.js';
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
    else if (k === '--expect-collision') current.collision = next();
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

// Fills the viewer template as the C++ side does (docs/replay.md); `name`, the replay file's
// name, goes into the config when given (the page's cut command uses it).
function fillViewer(template, bytes, name = null) {
  return template
    .replace('__OVERTAKE_CONFIG__', () => JSON.stringify(name ? { source: 'embedded', name } : { source: 'embedded' }).replace(/</g, '\\u003c'))
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
  await testCollisionMarks(page, replay, spec);
  await testNearMisses(page, replay, name, artifacts);
  await testCutOrigin(page, replay, spec, name, artifacts);
  await testCutCommand(page, replay, spec);

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

// A collision's marker and banner name its kind, its contact and whether it was the ego's
// fault (a file from before collisions were classified: neither; from before contacts: no
// contact); an at-fault mark is filled, another outlined. Each contact is marked once, at its
// first incident; the rubric's latched incidents of it (one per second of contact) get lighter
// marks that say so, and its banner shows once. `spec.collision` is a text the first collision
// must say.
async function testCollisionMarks(page, replay, spec) {
  let k = -1;
  for (let j = 0; j < replay.incidents && k < 0; ++j) if (replay.incidentTypeName(replay.incType[j]) === 'collision') k = j;
  if (k < 0) {
    if (spec.collision) check(false, `the replay has a collision (expected: ${spec.collision})`);
    return;
  }
  const cls = replay.incidentClass(k);
  const want = incidentText('collision', replay.incValue[k], cls, replay.incidentContact(k));
  const step = replay.step[replay.incFrame[k]];
  const mark = page.locator(`#incident-markers .marker[data-type="collision"][data-step="${step}"]:not(.latched)`).first();
  const seen = await mark.evaluate((m) => ({
    title: m.title, fault: m.dataset.atFault ?? null, kind: m.dataset.kind ?? null, contact: m.dataset.contact ?? null,
    fill: getComputedStyle(m).backgroundColor, border: getComputedStyle(m).borderTopWidth,
  }));
  check(seen.title.includes(want), `the collision's marker says "${want}" (${seen.title})`);
  if (spec.collision) check(seen.title.includes(spec.collision), `the first collision is "${spec.collision}"`);
  if (cls) {
    check(seen.kind === cls.kind && seen.fault === String(cls.atFault), `the marker carries the kind and fault (${seen.kind}, ${seen.fault})`);
    check(cls.atFault ? seen.border === '0px' : seen.border !== '0px',
      `${cls.atFault ? 'an at-fault collision\'s marker is filled' : 'a collision not at fault has an outlined marker'} (border ${seen.border}, fill ${seen.fill})`);
  } else {
    check(seen.kind === null && seen.fault === null && !/at fault/.test(seen.title), `an unclassified collision's marker says no fault (${seen.title})`);
  }
  const contact = replay.incidentContact(k);
  check(contact < 0 ? seen.contact === null && !/contact \d/.test(seen.title) : seen.contact === String(contact + 1) && seen.title.includes(`(contact ${contact + 1})`),
    `the marker names its contact (${contact < 0 ? 'none in this replay' : `contact ${contact + 1}`}: ${seen.contact})`);
  await mark.evaluate((m) => m.click()); // as a click on it, wherever other marks lie
  const banners = await page.locator('#incident-banners .banner[data-type="collision"]').allTextContents();
  check(banners.includes(want), `the banner says "${want}" (${banners.join(' | ')})`);

  // every contact once: a full mark at its first incident, lighter ones for its latched repeats
  const { list, repeat } = replay.contacts();
  if (!list.length) return;
  const marks = await page.evaluate(() => [...document.querySelectorAll('#incident-markers .marker[data-type="collision"]')].map((m) => ({
    step: Number(m.dataset.step), contact: m.dataset.contact ?? null, latched: m.classList.contains('latched'), title: m.title,
    opacity: Number(getComputedStyle(m).opacity), height: m.getBoundingClientRect().height,
  })));
  const full = marks.filter((m) => m.contact !== null && !m.latched);
  const firsts = list.map((c) => replay.step[replay.incFrame[c.first]]);
  check(full.length === list.length && full.every((m, i) => m.step === firsts[i] && m.contact === String(list[i].contact + 1)),
    `each of the ${list.length} contacts is marked once, at its first incident (${full.map((m) => `${m.contact}@${m.step}`).join(', ')})`);
  const repeats = [...repeat].filter(Boolean).length;
  const latched = marks.filter((m) => m.latched);
  if (repeats > 0) {
    const normal = full[0];
    check(latched.length > 0 && latched.every((m) => m.opacity < 1 && m.height < normal.height && m.contact !== null && /still in contact/.test(m.title)),
      `the rubric's ${repeats} latched incidents of a contact are marked lighter (${latched.length} marks, opacity ${latched.map((m) => m.opacity).join(', ')})`);
    const c = list.find((x) => x.incidents > 1);
    check(latched.some((m) => m.title.includes(latchedText(2, c.incidents))), `a latched mark says "${latchedText(2, c.incidents)}"`);
    // its banner shows once while the contact goes on (at its last latched incident)
    let last = -1;
    for (let j = 0; j < replay.incidents; ++j) if (replay.incidentContact(j) === c.contact) last = j;
    await page.evaluate((s) => window.overtakeViewer.seek(s), replay.step[replay.incFrame[last]]);
    const shown = await page.evaluate(() => [...document.querySelectorAll('#incident-banners .banner[data-contact]')].map((b) => b.dataset.contact));
    check(shown.filter((x) => x === String(c.contact + 1)).length === 1, `a contact's banner shows once however many incidents it has (${shown.join(', ')})`);
  } else {
    check(latched.length === 0, 'no latched marks without latched incidents');
  }
}

// A cut scenario's replay says where it was cut from and marks the moment on the timeline;
// another replay has neither. A replay whose frames start later than step 0 (a cut keeps the
// run's clock) shows that clock: time label, slider, charts.
async function testCutOrigin(page, replay, spec, name, artifacts) {
  const c = replay.cutFrom;
  if (spec.cut) check(c !== null, `the replay was cut from another (provenance.cut_from: ${JSON.stringify(replay.header.provenance?.cut_from)})`);
  const seen = await page.evaluate(() => {
    const bar = document.getElementById('cut-origin');
    const mark = document.getElementById('cut-mark');
    return { hidden: bar.hidden, text: bar.textContent, markHidden: mark.hidden, markStep: mark.dataset.step, markLeft: mark.style.left };
  });
  if (!c) {
    check(seen.hidden && seen.markHidden, `a replay that was not cut shows no cut origin and no cut mark (bar ${seen.hidden ? 'hidden' : 'shown'}, mark ${seen.markHidden ? 'hidden' : 'shown'})`);
  } else {
    const want = cutOriginText(c);
    check(!seen.hidden && seen.text.includes(want), `the page says where the scenario was cut from: "${want}" (${seen.hidden ? 'hidden' : seen.text})`);
    const step = Math.round(c.atS / replay.stepS);
    const s0 = replay.step[0];
    const where = (step - s0) / Math.max(1, replay.step[replay.frames - 1] - s0);
    check(!seen.markHidden && Number(seen.markStep) === step && Math.abs(parseFloat(seen.markLeft) - 100 * where) < 0.01,
      `the timeline marks the moment t ${c.atS.toFixed(2)} s, step ${step} (${seen.markHidden ? 'no mark' : `step ${seen.markStep} at ${seen.markLeft}`})`);
    await page.click('#cut-origin-seek');
    const now = Number(await page.getAttribute('#viewer', 'data-step'));
    check(now === replay.step[replay.frameOfStep(step)], `the cut origin's button seeks to the moment (step ${now})`);
    await page.locator('#controls').screenshot({ path: join(artifacts, `${name}-cut-mark.png`) });
  }
  if (replay.step[0] === 0) return;
  // the run's clock: the first frame is at t > 0, the slider's ends are the first and last frame
  const first = await page.evaluate((s) => {
    window.overtakeViewer.seek(s);
    return { label: document.getElementById('time-label').textContent, slider: document.getElementById('scrubber').value, max: document.getElementById('scrubber').max };
  }, replay.step[0]);
  check(first.label.startsWith(`${clock(replay.time[0])} / ${clock(replay.time[replay.frames - 1])} · step ${replay.step[0]}`) &&
    first.slider === '0' && Number(first.max) === replay.frames - 1,
  `a replay from step ${replay.step[0]} starts at its own time (${first.label}; slider ${first.slider} of ${first.max})`);
  // the slider's middle is the middle frame
  const mid = await page.evaluate(() => {
    const el = document.getElementById('scrubber');
    el.value = String(Math.floor(Number(el.max) / 2));
    el.dispatchEvent(new Event('input', { bubbles: true }));
    return Number(document.getElementById('viewer').dataset.step);
  });
  const midStep = replay.step[Math.floor((replay.frames - 1) / 2)];
  check(mid === midStep, `the slider's middle is the middle frame (step ${mid}, want ${midStep})`);
  // the charts span the replay's times: the playhead sits in proportion, a click in the
  // middle of the speed chart seeks to about the middle
  await page.selectOption('#chart-window', '0');
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(() => r()))));
  const head = await page.evaluate(() => {
    const over = document.querySelector('#chart-speed .u-over');
    const h = over.querySelector('.playhead');
    const m = /translateX\(([-\d.]+)px\)/.exec(h.style.transform);
    return { shown: h.style.display !== 'none', x: m ? Number(m[1]) : NaN, width: over.clientWidth };
  });
  check(head.shown && Math.abs(head.x / head.width - 0.5) < 0.02, `the charts' playhead is in the middle at the middle frame (${head.x} of ${head.width} px)`);
  const box = await page.locator('#chart-speed .u-over').boundingBox();
  await page.mouse.click(box.x + box.width * 0.5, box.y + box.height * 0.5);
  const clicked = Number(await page.getAttribute('#viewer', 'data-step'));
  const span = replay.step[replay.frames - 1] - replay.step[0];
  check(Math.abs(clicked - midStep) < span * 0.02, `a click in the middle of the speed chart seeks to about the middle (step ${clicked}, middle ${midStep})`);
}

// The cut control: the command for the current time, following seeks and playback; the
// traffic choice; copied (or, without the clipboard API, selected for the user to copy).
async function testCutCommand(page, replay, spec) {
  const known = await page.evaluate(() => window.overtakeViewer.fileName);
  if (spec.fileName !== undefined) check(known === spec.fileName, `the page knows the replay's file name from its config (${known})`);
  else check(known === null || known === basename(spec.replay), `the page's replay file name is none or the file's (${known})`);
  const closed = await page.evaluate(() => ({ button: !document.getElementById('btn-cut').hidden, box: document.getElementById('cut-box').hidden }));
  check(closed.button && closed.box, `the cut button is shown, its box closed (${JSON.stringify(closed)})`);
  await page.click('#btn-cut');
  const command = () => page.evaluate(() => ({
    text: document.getElementById('cut-command').textContent,
    step: Number(document.getElementById('viewer').dataset.step),
    open: !document.getElementById('cut-box').hidden,
  }));
  for (const f of [0.3, 0.85]) {
    const step = replay.step[Math.floor((replay.frames - 1) * f)];
    await page.evaluate((s) => window.overtakeViewer.seek(s), step);
    const got = await command();
    const want = cutCommand(known, replay.time[replay.frameOfStep(step)]);
    check(got.open && got.text === want, `at step ${step} the cut box shows "${want}" (${got.open ? got.text : 'closed'})`);
  }
  await page.evaluate((s) => { window.overtakeViewer.seek(s); window.overtakeViewer.setSpeed(16); window.overtakeViewer.play(); }, replay.step[0]);
  await page.waitForTimeout(300);
  await page.evaluate(() => window.overtakeViewer.pause());
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
  const played = await command();
  const wantPlayed = cutCommand(known, replay.time[replay.frameOfStep(played.step)]);
  check(played.step > replay.step[0] && played.text === wantPlayed, `while playing the command follows the time (step ${played.step}: ${played.text})`);
  await page.selectOption('#cut-traffic', 'replayed');
  const replayed = await command();
  check(replayed.text === cutCommand(known, replay.time[replay.frameOfStep(replayed.step)], 'replayed'), `replayed traffic adds --traffic replayed (${replayed.text})`);
  await page.selectOption('#cut-traffic', 'reactive');
  // copy: with the clipboard API the status says copied (and the clipboard holds the command
  // where the test may read it); without it, the command is selected
  await page.click('#btn-cut-copy');
  await page.waitForFunction(() => document.getElementById('cut-copy-status').textContent !== '', null, { timeout: 5000 });
  const copied = await page.evaluate(async () => {
    const cmd = document.getElementById('cut-command').textContent;
    let clip = null;
    try {
      clip = await navigator.clipboard.readText();
    } catch {
      clip = null; // no permission to read it back: the status is what there is to check
    }
    return { cmd, clip, status: document.getElementById('cut-copy-status').textContent, selection: String(window.getSelection()) };
  });
  check((copied.status === 'copied' && (copied.clip === null || copied.clip === copied.cmd)) || (/selected/.test(copied.status) && copied.selection === copied.cmd),
    `copy copies the command or selects it (${copied.status}${copied.clip !== null ? `; clipboard: ${copied.clip}` : ''})`);
  const fallback = await page.evaluate(() => {
    Object.defineProperty(navigator, 'clipboard', { value: undefined, configurable: true });
    window.getSelection().removeAllRanges();
    document.getElementById('btn-cut-copy').click();
    const out = { status: document.getElementById('cut-copy-status').textContent, selection: String(window.getSelection()), cmd: document.getElementById('cut-command').textContent };
    delete navigator.clipboard;
    return out;
  });
  check(/selected/.test(fallback.status) && fallback.selection === fallback.cmd, `without the clipboard API the command is selected to copy (${fallback.status}: ${fallback.selection})`);
  await page.click('#btn-cut');
  check(await page.locator('#cut-box').isHidden(), 'the cut button closes its box');
}

// The near-miss chart holds every TTC and headway of the replay (none is a gap), the HUD
// shows them, and the status line what the report says of collisions and near misses.
async function testNearMisses(page, replay, name, artifacts) {
  let finite = 0;
  let probe = -1;
  for (let i = 0; i < replay.frames; ++i) {
    for (const col of [replay.ttcAhead, replay.ttcEntering, replay.headway]) if (Number.isFinite(col[i])) finite += 1;
    if (probe < 0 && Number.isFinite(replay.ttcAhead[i]) && i > replay.frames / 4) probe = i;
  }
  const chart = await page.evaluate(() => {
    const el = document.getElementById('chart-safety');
    return el ? { canvases: el.querySelectorAll('canvas').length, points: Number(el.dataset.points), title: el.querySelector('.u-title')?.textContent } : null;
  });
  check(chart && chart.canvases > 0 && chart.points === finite,
    `the near-miss chart shows the ${finite} TTC and headway values (${chart ? `${chart.points} points: ${chart.title}` : 'no chart'})`);
  if (replay.safetyFrames > 0) {
    check(finite > 0, `the replay records TTC or headway (${replay.safetyFrames} frames carry them, ${finite} values)`);
  } else {
    check(/not in this replay/.test(chart?.title || ''), `a replay without TTC says so on the chart (${chart?.title})`);
  }
  if (probe >= 0) {
    const hud = await page.evaluate((s) => {
      window.overtakeViewer.seek(s);
      return { ttc: document.getElementById('hud-ttc').textContent, headway: document.getElementById('hud-headway').textContent };
    }, replay.step[probe]);
    const wantHeadway = Number.isFinite(replay.headway[probe]) ? replay.headway[probe].toFixed(2) : '–';
    check(hud.ttc === replay.ttcAhead[probe].toFixed(2) && hud.headway === wantHeadway,
      `after seek(${replay.step[probe]}) the HUD shows TTC ${hud.ttc} s, headway ${hud.headway} s (recorded ${replay.ttcAhead[probe].toFixed(2)}, ${wantHeadway})`);
    await page.locator('#chart-safety').screenshot({ path: join(artifacts, `${name}-near-misses.png`) });
  }
  const status = await page.textContent('#status');
  const want = safetyStatusText(replay.report);
  check(want === '' ? !/near miss|at fault/.test(status) : status.includes(want), `the status line says "${want || 'nothing of near misses'}" (${status})`);
}

// The bench report object (docs/replay.md) from a bench --out folder: bench.json, the runs,
// and summary.json's rows, pairs and verdicts when the folder has one (without, the page
// summarizes the runs itself).
function benchObject(dir) {
  const bench = JSON.parse(readFileSync(join(dir, 'bench.json'), 'utf8'));
  bench.runs = readFileSync(join(dir, 'runs.jsonl'), 'utf8').split('\n').filter(Boolean).map((l) => JSON.parse(l));
  bench.runs.forEach((r, i) => { r.replay = i % 2 === 0 ? `replays/run-${i}.html` : null; });
  if (existsSync(join(dir, 'summary.json'))) {
    const summary = JSON.parse(readFileSync(join(dir, 'summary.json'), 'utf8'));
    if (Array.isArray(summary.rows)) bench.summary = summary.rows;
    if (Array.isArray(summary.pairs)) bench.pairs = summary.pairs;
    if (summary.verdicts) bench.verdicts = summary.verdicts;
  }
  return bench;
}

// The report page's data element, and a copy of the page with other data in it.
const BENCH_ELEMENT = /(<script id="overtake-bench" type="application\/json">)([\s\S]*?)(<\/script>)/;
const benchOfPage = (html) => JSON.parse(html.match(BENCH_ELEMENT)[2]);
const pageWithBench = (html, bench) => html.replace(BENCH_ELEMENT, (m, open, _, close) => `${open}${JSON.stringify(bench).replace(/</g, '\\u003c')}${close}`);

// The keys a summary row had before intervals, collision classes and near misses.
const OLDER_ROW_KEYS = ['policy', 'traffic', 'runs', 'total_miles', 'mean_speed_mph', 'incidents', 'incidents_per_100mi',
  'incidents_per_100mi_by_type', 'incident_free_miles_median', 'incident_free_miles_worst', 'peak_acceleration_mps2',
  'peak_jerk_mps3', 'peak_strict_acceleration_mps2', 'peak_strict_jerk_mps3', 'timing'];

// The verdict of A's difference from B with its interval, as a bench from before the tests
// gave it (better when it leaves out 0 on A's side).
const verdictOf = (d, ci, higherIsBetter) => (ci[0] > 0 || ci[1] < 0 ? ((d > 0) === higherIsBetter ? 'better' : 'worse') : 'no difference');
const MIRRORED = { better: 'worse', worse: 'better' };

// How the verdicts were reached, as the bench writes it (docs/replay.md).
const VERDICT_METHOD = {
  alpha: 0.05, correction: 'Holm', family_tests: 0, min_seeds: 8, mean_test: "paired t-test on the seeds' linearized differences",
  rate_test: 'exact sign-flip randomization test over seeds', mean_interval: 'symmetric bootstrap-t over seeds',
  rate_interval: "exact (Garwood) interval on the events over the seeds' dispersion (quasi-Poisson, t-scaled); no event: one-sided upper bound",
  difference_interval: "means: paired symmetric bootstrap-t; rates: MOVER from both rates' intervals",
};

// The rows of a bench of today made up from `rows` (plausible, not computed: the page only
// shows them): intervals, collisions as contacts beside the rubric's count (the first row's
// at-fault rate with no event: a one-sided interval), near misses, precision, a warning.
function todaysRows(rows) {
  return rows.map((r0, i) => {
    const r = structuredClone(r0);
    const rate = (v) => [v * 0.6, v * 1.5 + 2.5];
    r.intervals = null;
    r.warnings = i === 1 ? ['at_fault_collisions_per_100mi: one seed holds 100% of the events; the interval cannot tell how rare such seeds are'] : [];
    r.mean_speed_mph_ci ??= [r.mean_speed_mph - 0.8, r.mean_speed_mph + 0.6];
    r.incidents_per_100mi_ci ??= rate(r.incidents_per_100mi);
    r.incidents_per_100mi_by_type_ci = Object.fromEntries(Object.entries(r.incidents_per_100mi_by_type || {}).map(([k, v]) => [k, rate(v)]));
    r.incident_free_miles_median_ci ??= [r.incident_free_miles_median * 0.9, r.incident_free_miles_median * 1.05];
    const per = 100 / Math.max(1e-9, r.total_miles);
    r.collisions = i === 0
      ? { total: 0, per_100mi: 0, per_100mi_ci: [0, 3 * per], at_fault: 0, at_fault_per_100mi: 0, at_fault_per_100mi_ci: [0, 3 * per], by_kind: {}, rubric_incidents: 0, rubric_per_100mi: 0 }
      : { total: 1, per_100mi: per, per_100mi_ci: rate(per), at_fault: 1, at_fault_per_100mi: per, at_fault_per_100mi_ci: rate(per), by_kind: { ego_hit_car_ahead: 1 }, rubric_incidents: 3, rubric_per_100mi: 3 * per };
    r.near_misses ??= { episodes: 2, per_100mi: 2 * per, per_100mi_ci: rate(2 * per), min_ttc_ahead_s: 0.9, min_ttc_entering_s: null, min_time_headway_s: 0.4,
      share_ttc_below: 0.012, share_headway_below: 0.2, ttc_threshold_s: 1.5, headway_threshold_s: 1.0 };
    r.near_misses.per_100mi_ci ??= rate(r.near_misses.per_100mi);
    r.precision = { mean_speed_mph: { half_width: 0.7, seeds_to_halve: 4 * r.runs }, incidents_per_100mi: { half_width: 3.1, seeds_to_halve: 4 * r.runs + 1 },
      at_fault_collisions_per_100mi: null };
    return r;
  });
}

// Pairs of today for `rows`: every two policies on each traffic profile, each figure with its
// test, P(improvement) with its interval and a verdict; the verdicts cycle through better,
// worse, no difference and too few seeds, and one figure has no data.
function todaysPairs(rows) {
  const pairs = [];
  const verdicts = ['better', 'worse', 'no difference', 'too few seeds'];
  let n = 0;
  const fig = (ca, cb, higher) => {
    const verdict = verdicts[n++ % verdicts.length];
    const few = verdict === 'too few seeds';
    // a difference of the verdict's sign (better: up for speed, down for rates)
    const sign = verdict === 'better' ? (higher ? 1 : -1) : verdict === 'worse' ? (higher ? -1 : 1) : 0;
    const d = sign === 0 ? ca - cb : sign * (Math.abs(ca - cb) + 1.5);
    const ci = few ? null : sign === 0 ? [d - 2, d + 2] : [d - 1, d + 1];
    const p = few ? null : 0.5 + 0.3 * (higher ? Math.sign(d) : -Math.sign(d));
    return { candidate: cb + d, base: cb, difference: d, ci, p_value: few ? null : sign ? 0.0004 : 0.3, p_adjusted: few ? null : sign ? 0.004 : 1,
      probability_of_improvement: p, probability_of_improvement_ci: few ? null : [p - 0.1, Math.min(1, p + 0.1)], verdict };
  };
  for (const t of [...new Set(rows.map((r) => r.traffic))]) {
    const mine = rows.filter((r) => r.traffic === t);
    for (let i = 0; i < mine.length; ++i) {
      for (let j = i + 1; j < mine.length; ++j) {
        const a = mine[i];
        const b = mine[j];
        pairs.push({ traffic: t, policy: a.policy, versus: b.policy, seeds: a.runs, figures: {
          mean_speed_mph: fig(a.mean_speed_mph, b.mean_speed_mph, true),
          incidents_per_100mi: fig(a.incidents_per_100mi, b.incidents_per_100mi, false),
          collisions_per_100mi: fig(1, 1, false),
          at_fault_collisions_per_100mi: fig(1, 0.5, false),
          near_misses_per_100mi: null,
        } });
      }
    }
  }
  return pairs;
}

// The bench data with every key of today's bench filled in (made up), and, in place of its
// pairs (the page's own are checked on the page itself), pairs of every verdict.
// Today's bench with two `overtake risk` estimates (bench --risk): one with no event (a bound),
// one with a rate; the chart draws them hollow on a log rate axis, joined as the policy's frontier.
function withRisk(bench) {
  const b = withTodaysKeys(bench);
  const row = (b.summary || [])[0] || {};
  const point = (label, rate, ci, bound, faster) => ({ folder: `risk-${label}`, label: `${row.policy} ${label} (risk)`, policy: row.policy, config: '', traffic: row.traffic,
    map: null, rate_per_100mi: rate, ci95_per_100mi: ci, upper_bound_only: bound, mean_speed_mph: (row.mean_speed_mph || 45) + faster, base_miles: 4000 });
  b.risk = [point('safe', 0, [0, 0.066], true, 0.3), point('weak', 0.064, [0.013, 0.19], false, 0.8)];
  return b;
}

function withTodaysKeys(bench) {
  const b = structuredClone(bench);
  b.summary = todaysRows(b.summary);
  b.pairs = todaysPairs(b.summary);
  b.verdicts = { ...VERDICT_METHOD, family_tests: b.pairs.length * 4 };
  return b;
}

// A bench of nine policies with long names on two traffic profiles (made up from the first
// row and its runs), crowded: close speeds, most without an at-fault collision. Its charts'
// labels must not overlap.
function withManyPolicies(bench) {
  const b = structuredClone(bench);
  const [row] = todaysRows([b.summary[0], b.summary[0]]).slice(1);
  const policies = Array.from({ length: 9 }, (_, i) => `a-policy-with-a-long-name-${i + 1}`);
  const traffic = ['faithful', 'calm'];
  b.policies = policies;
  b.traffic = traffic;
  b.summary = [];
  for (const t of traffic) {
    policies.forEach((p, i) => {
      const r = structuredClone(row);
      r.policy = p;
      r.traffic = t;
      r.mean_speed_mph = 44 + (i % 3) * 0.15 + (t === 'calm' ? 0.3 : 0);
      r.mean_speed_mph_ci = [r.mean_speed_mph - 0.7, r.mean_speed_mph + 0.6];
      const rate = i % 4 === 0 ? 2 + i * 0.2 : 0;
      r.collisions = { ...r.collisions, at_fault_per_100mi: rate, at_fault_per_100mi_ci: rate ? [rate * 0.4, rate * 2.2] : [0, 3.1] };
      b.summary.push(r);
    });
  }
  const runs = b.runs.filter((r) => r.config.policy === b.runs[0].config.policy && r.config.traffic === b.runs[0].config.traffic);
  b.runs = [];
  for (const t of traffic) for (const p of policies) for (const r of runs) b.runs.push({ ...structuredClone(r), config: { ...r.config, policy: p, traffic: t }, replay: null });
  b.pairs = todaysPairs(b.summary);
  b.verdicts = { ...VERDICT_METHOD, family_tests: b.pairs.length * 4 };
  b.combinations = b.runs.length;
  return b;
}

// The bench data as an older build wrote it: summary rows of the older keys, no pairs, runs
// without collisions at fault or near misses.
function asOlderBench(bench) {
  const b = structuredClone(bench);
  b.summary = b.summary.map((r) => Object.fromEntries(OLDER_ROW_KEYS.filter((k) => k in r).map((k) => [k, r[k]])));
  delete b.pairs;
  delete b.verdicts;
  for (const r of b.runs) {
    delete r.collisions;
    delete r.safety;
    for (const i of r.incidents || []) {
      delete i.kind;
      delete i.at_fault;
      delete i.contact;
    }
  }
  return b;
}

// The bench data as a build from before contacts and tests wrote it: collisions counted for
// every second of contact (no rubric's count, no contacts in the runs), zero-event intervals
// two-sided (no `intervals` key), pairs without p-values or an interval of P(improvement),
// their verdicts from the interval, no `verdicts`.
function asBeforeContacts(bench) {
  const b = withTodaysKeys(bench);
  delete b.verdicts;
  for (const r of b.summary) {
    delete r.intervals;
    delete r.warnings;
    delete r.collisions.rubric_incidents;
    delete r.collisions.rubric_per_100mi;
  }
  for (const p of b.pairs) {
    for (const [k, f] of Object.entries(p.figures)) {
      if (!f) continue;
      if (!f.ci) f.ci = [f.difference - 1, f.difference + 1];
      f.probability_of_improvement ??= 0.5;
      delete f.p_value;
      delete f.p_adjusted;
      delete f.probability_of_improvement_ci;
      f.verdict = verdictOf(f.difference, f.ci, k === 'mean_speed_mph');
    }
  }
  for (const r of b.runs) {
    if (!r.collisions) continue;
    r.collisions.total = (r.incident_counts || {}).collision || 0;
    delete r.collisions.contacts;
    delete r.collisions.rubric_incidents;
    for (const i of r.incidents || []) delete i.contact;
  }
  return b;
}

// Copies of the report page beside it: with today's keys, with many policies, as a bench from
// before contacts, as an older bench's, and without a summary (the page summarizes the runs
// itself). Returns [{path, name, expect}].
function reportVariants(path) {
  const html = readFileSync(path, 'utf8');
  const bench = benchOfPage(html);
  const noSummary = structuredClone(bench);
  delete noSummary.summary;
  delete noSummary.pairs;
  delete noSummary.verdicts;
  return [
    { name: 'today', expect: 'today', bench: withTodaysKeys(bench) },
    { name: 'risk', expect: 'risk', bench: withRisk(bench) },
    { name: 'many', expect: 'many', bench: withManyPolicies(bench) },
    { name: 'before-contacts', expect: 'before-contacts', bench: asBeforeContacts(bench) },
    { name: 'older', expect: 'older', bench: asOlderBench(bench) },
    { name: 'no-summary', expect: 'no-summary', bench: noSummary },
  ].map((v) => {
    const out = join(dirname(path), `report-${v.name}.html`);
    writeFileSync(out, pageWithBench(html, v.bench));
    return { path: out, name: v.name, expect: v.expect };
  });
}

// The matrices of the pairs against the data: for each figure and traffic profile a grid of
// every policy against every other; the cell of each pair (row policy, column versus) has its
// verdict and difference, the mirror cell (versus, policy) the mirrored verdict and the negated
// difference; verdicts are told apart by colour and by mark; each cell's hover text holds the
// difference's interval, P(row better) with its interval and the adjusted p-value the data has.
async function testMatrices(page) {
  const got = await page.evaluate(() => {
    const pairs = (window.overtakeReport || {}).pairs || [];
    const tables = [...document.querySelectorAll('#matrices table.matrix')].map((t) => ({
      figure: t.dataset.figure, traffic: t.dataset.traffic,
      cols: [...t.querySelectorAll('thead th')].slice(1).map((th) => th.title || th.textContent), // numbered with long names: the title names it
      rows: [...t.querySelectorAll('tbody tr')].map((tr) => ({
        policy: tr.dataset.policy,
        cells: [...tr.querySelectorAll('td')].slice(1).map((td) => ({ text: td.textContent, title: td.title, cls: td.className, ...td.dataset,
          background: getComputedStyle(td).backgroundColor, image: getComputedStyle(td).backgroundImage })),
      })),
    }));
    const legend = [...document.querySelectorAll('#matrix-legend .m-key')].map((k) => k.textContent);
    return { pairs, tables, legend, method: document.getElementById('pairs-method').textContent };
  });
  const pairs = got.pairs;
  const figures = [...new Set(pairs.flatMap((p) => Object.entries(p.figures || {}).filter(([, f]) => f && typeof f === 'object').map(([k]) => k)))];
  const traffic = [...new Set(pairs.map((p) => p.traffic))];
  check(got.tables.length === figures.length * traffic.length, `a matrix per figure and traffic profile (${got.tables.length} of ${figures.length} × ${traffic.length})`);
  let cells = 0;
  let bad = [];
  const seen = {};
  for (const p of pairs) {
    for (const [key, f] of Object.entries(p.figures || {})) {
      const t = got.tables.find((x) => x.figure === key && x.traffic === p.traffic);
      if (!t) {
        if (f) bad.push(`no matrix of ${key} on ${p.traffic}`);
        continue;
      }
      const cellOf = (a, b) => {
        const row = t.rows.find((r) => r.policy === a);
        const j = t.cols.indexOf(b);
        return row && j >= 0 ? row.cells[j] : null;
      };
      const c = cellOf(p.policy, p.versus);
      const m = cellOf(p.versus, p.policy);
      if (!c || !m) {
        bad.push(`${key} ${p.policy} vs ${p.versus}: no cell`);
        continue;
      }
      cells += 2;
      if (!f) {
        if (c.verdict !== 'none' || m.verdict !== 'none') bad.push(`${key} ${p.policy} vs ${p.versus}: a figure without data is not blank`);
        continue;
      }
      const mirrored = MIRRORED[f.verdict] ?? f.verdict;
      if (c.verdict !== f.verdict || m.verdict !== mirrored) bad.push(`${key} ${p.policy} vs ${p.versus}: verdicts ${c.verdict} / ${m.verdict}, want ${f.verdict} / ${mirrored}`);
      if (c.mirrored !== 'false' || m.mirrored !== 'true') bad.push(`${key} ${p.policy} vs ${p.versus}: the mirror cell is not marked so`);
      if (Math.abs(Number(c.difference) - f.difference) > 1e-9 || Math.abs(Number(m.difference) + f.difference) > 1e-9) {
        bad.push(`${key} ${p.policy} vs ${p.versus}: differences ${c.difference} / ${m.difference}, want ${f.difference} and its negation`);
      }
      const ci = Array.isArray(f.ci) ? f.ci : null;
      const dec = (PAIR_FIGURES.find((x) => x.key === key) || { d: 2 }).d;
      if (ci && !(c.title.includes(`(${signed(ci[0], dec)} to ${signed(ci[1], dec)})`) && m.title.includes(`(${signed(-ci[1], dec)} to ${signed(-ci[0], dec)})`))) {
        bad.push(`${key} ${p.policy} vs ${p.versus}: the hover lacks the interval or its mirror (${c.title} / ${m.title})`);
      }
      if (typeof f.probability_of_improvement === 'number') {
        const pci = Array.isArray(f.probability_of_improvement_ci) ? f.probability_of_improvement_ci : null;
        const want = `P(${p.policy} better): ${f.probability_of_improvement.toFixed(2)}${pci ? ` (${pci[0].toFixed(2)}–${pci[1].toFixed(2)})` : ''}`;
        const wantMirror = `P(${p.versus} better): ${(1 - f.probability_of_improvement).toFixed(2)}${pci ? ` (${(1 - pci[1]).toFixed(2)}–${(1 - pci[0]).toFixed(2)})` : ''}`;
        if (!c.title.includes(want) || !m.title.includes(wantMirror)) bad.push(`${key} ${p.policy} vs ${p.versus}: the hover lacks "${want}" / "${wantMirror}"`);
      }
      if (typeof f.p_adjusted === 'number' && !(c.title.includes('Holm-adjusted') && m.title.includes('Holm-adjusted'))) bad.push(`${key} ${p.policy} vs ${p.versus}: the hover lacks the adjusted p-value`);
      for (const x of [c, m]) seen[x.verdict] = { background: x.background, image: x.image, mark: x.text.split(' ')[0] };
    }
  }
  bad = [...new Set(bad)];
  check(bad.length === 0, `every pair's cell and its mirror show the verdict, difference and hover text (${cells} cells${bad.length ? `; ${bad.slice(0, 3).join('; ')}` : ''})`);
  const diagonal = got.tables.every((t) => t.rows.every((r) => r.cells[t.cols.indexOf(r.policy)]?.verdict === 'self'));
  check(diagonal && got.tables.every((t) => t.rows.length === t.cols.length), 'each matrix is square, its diagonal blank');
  const kinds = Object.keys(seen).filter((v) => ['better', 'worse', 'no difference', 'too few seeds'].includes(v));
  const looks = new Set(kinds.map((v) => `${seen[v].background}|${seen[v].image}`));
  const marks = new Set(kinds.map((v) => seen[v].mark));
  check(looks.size === kinds.length && marks.size === kinds.length,
    `each verdict has a colour and a mark of its own (${kinds.map((v) => `${v}: ${seen[v].mark} ${seen[v].background}`).join('; ')})`);
  check(got.legend.length >= 4 && got.legend.some((l) => l.includes('better')) && got.legend.some((l) => l.includes('worse')), `the matrices have a legend (${got.legend.join(', ')})`);
  return { seen: kinds, method: got.method };
}

// The speed-against-safety chart against the rows: a point per row with both figures, an
// error bar each way per interval (a rate with no event: one-sided), the rows without collision
// figures named; no two labels of any chart overlap, and every scatter label was placed.
async function testScatterAndLabels(page, expect) {
  const got = await page.evaluate(() => {
    const rep = window.overtakeReport || {};
    const rows = rep.rows || [];
    const isCI = (c) => Array.isArray(c) && c.length === 2 && c.every((x) => typeof x === 'number');
    const num = (x) => typeof x === 'number' && Number.isFinite(x);
    const withFigures = rows.filter((r) => num(r.mean_speed_mph) && num((r.collisions || {}).at_fault_per_100mi));
    const risk = ((rep.bench || {}).risk || []).filter((e) => num(e.mean_speed_mph) && num(e.rate_per_100mi));
    const el = document.getElementById('chart-scatter');
    return {
      rows: rows.length,
      points: withFigures.length + risk.length,
      risk: risk.length,
      xBars: withFigures.filter((r) => isCI(r.collisions.at_fault_per_100mi_ci)).length + risk.filter((e) => isCI(e.ci95_per_100mi)).length,
      yBars: withFigures.filter((r) => isCI(r.mean_speed_mph_ci)).length,
      oneSided: withFigures.filter((r) => 'intervals' in r && r.collisions.at_fault_per_100mi === 0 && isCI(r.collisions.at_fault_per_100mi_ci) && r.collisions.at_fault_per_100mi_ci[0] === 0).length +
        risk.filter((e) => e.upper_bound_only).length,
      shown: el && !el.hidden ? { ...el.dataset } : null,
      leftOut: document.querySelector('#chart-scatter .left-out')?.textContent || '',
      leftOutHidden: document.querySelector('#chart-scatter .left-out')?.hidden ?? true,
      legend: [...document.querySelectorAll('#chart-scatter .scatter-legend .key')].map((k) => k.textContent.trim()),
      traffic: [...new Set(rows.map((r) => r.traffic))].length,
      boxes: rep.labelBoxes ? rep.labelBoxes() : {},
      canvas: (() => {
        const c = el && el.querySelector('canvas');
        return c ? { w: c.clientWidth, h: c.clientHeight } : null;
      })(),
    };
  });
  const d = got.shown || {};
  check(got.shown && Number(d.points) === got.points, `the speed-against-safety chart has a point per row with both figures (${d.points} of ${got.points})`);
  check(Number(d.xBars) === got.xBars && Number(d.yBars) === got.yBars,
    `and error bars both ways: ${d.xBars} across of ${got.xBars}, ${d.yBars} up of ${got.yBars}`);
  check(Number(d.oneSidedBars) === got.oneSided, `a rate with no event has a one-sided bar (${d.oneSidedBars} of ${got.oneSided})`);
  check(Number(d.riskPoints) === got.risk && d.xLog === String(got.risk > 0),
    `risk estimates are hollow points (${d.riskPoints} of ${got.risk}), the rate axis logarithmic with any (${d.xLog})`);
  if (got.risk > 0) check(got.legend.filter((k) => /\(risk\)$/.test(k)).length === got.risk, `the legend names each risk estimate (${got.legend.join(', ')})`);
  if (got.risk > 1) check(d.frontiers === '1', `the estimates of one policy are joined into its frontier (${d.frontiers} curves)`);
  if (got.points < got.rows) check(!got.leftOutHidden && /Left out/.test(got.leftOut), `the rows left out are named (${got.leftOut})`);
  if (got.points > 0) {
    check(got.legend.filter((k) => / traffic$/.test(k)).length === got.traffic, `the legend tells the traffic profiles apart (${got.legend.join(', ')})`);
    check(Number(d.unplaced) === 0, `every label of the speed-against-safety chart is placed (${d.labelMode}, ${d.unplaced} not placed)`);
  }
  let total = 0;
  const clashes = [];
  for (const [id, boxes] of Object.entries(got.boxes)) {
    total += boxes.length;
    for (const [i, j] of overlapping(boxes)) clashes.push(`${id}: "${boxes[i].text}" and "${boxes[j].text}"`);
  }
  check(clashes.length === 0, `no two labels overlap (${total} labels in ${Object.keys(got.boxes).length} charts${clashes.length ? `: ${clashes.slice(0, 4).join('; ')}` : ''})`);
  if (expect === 'many') {
    check(got.points >= 16 && (got.boxes['chart-scatter'] || []).length === got.points, `with nine policies on two profiles every point has a label (${(got.boxes['chart-scatter'] || []).length} of ${got.points})`);
    const numbered = await page.evaluate(() => ({ modes: [...document.querySelectorAll('.chart[data-label-mode]')].map((c) => `${c.id}:${c.dataset.labelMode}`),
      legend: !document.getElementById('slot-legend').hidden ? document.querySelectorAll('#slot-legend span').length : 0 }));
    const some = numbered.modes.some((m) => m.endsWith(':numbers'));
    check(!some || numbered.legend === got.rows, `the bars' numbers are named in a legend (${numbered.modes.join(', ')}; ${numbered.legend} entries)`);
  }
}

// What the report page shows of intervals, error bars, precision and pairs, against what its
// data holds: each is shown when (and only when) the data has it.
async function testReportFigures(page, expect) {
  const got = await page.evaluate(() => {
    const rep = window.overtakeReport || {};
    const rows = rep.rows || [];
    const bench = rep.bench || {};
    const isCI = (c) => Array.isArray(c) && c.length === 2 && c.every((x) => typeof x === 'number');
    const visible = (id) => Boolean(document.getElementById(id)) && !document.getElementById(id).hidden;
    const bars = (id) => Number(document.getElementById(id)?.dataset.errorBars || 0);
    const cells = (sel) => [...document.querySelectorAll(sel)];
    return {
      rows: rows.length,
      speedCI: rows.filter((r) => isCI(r.mean_speed_mph_ci)).length,
      incidentsCI: rows.filter((r) => isCI(r.incidents_per_100mi_ci)).length,
      fault: rows.filter((r) => typeof (r.collisions || {}).at_fault_per_100mi === 'number').length,
      faultCI: rows.filter((r) => isCI((r.collisions || {}).at_fault_per_100mi_ci)).length,
      precision: rows.filter((r) => r.precision && typeof r.precision === 'object' && Object.values(r.precision).some((p) => p && typeof p === 'object')).length,
      fewSeeds: rows.filter((r) => typeof r.intervals === 'string').length,
      warnings: rows.reduce((a, r) => a + (Array.isArray(r.warnings) ? r.warnings.length : 0), 0),
      notes: cells('#summary tr.notes-row td').map((td) => td.textContent),
      pairs: Array.isArray(bench.pairs) ? bench.pairs.length : 0,
      verdictsObject: Boolean(bench.verdicts),
      intervalCells: cells('#summary tbody td').filter((td) => /\d \((\d[\d.]*–\d[\d.]*|≤ \d[\d.]*)\)/.test(td.textContent)).length,
      oneSidedCells: cells('#summary tbody td').filter((td) => /^0\.0+ \(≤ \d[\d.]*\)$/.test(td.textContent)).length,
      summaryText: cells('#summary tbody tr:first-child td').map((td) => td.textContent).join(' | '),
      headers: cells('#summary thead th').map((th) => th.textContent).join(' | '),
      bars: { speed: bars('chart-speed'), incidents: bars('chart-incidents'), fault: bars('chart-fault') },
      faultChart: visible('chart-fault') && document.querySelectorAll('#chart-fault canvas').length > 0,
      precisionShown: visible('precision-section') ? document.querySelectorAll('#precision tbody tr').length : 0,
      pairsShown: visible('pairs-section') ? document.querySelectorAll('#pairs tbody tr').length : 0,
      pairText: cells('#pairs tbody tr:first-child td').map((td) => td.textContent).join(' | '),
      verdicts: cells('#pairs td.verdict').map((td) => ({ text: td.textContent, cls: td.className })),
      method: document.getElementById('pairs-method')?.textContent || '',
      collisionsNote: visible('summary-collisions') ? document.getElementById('summary-collisions').textContent : '',
    };
  });
  console.log(`  summary: ${got.summaryText}`);
  if (got.speedCI > 0) {
    check(got.intervalCells >= got.speedCI, `the summary shows intervals (${got.intervalCells} cells with one)`);
  } else {
    check(got.intervalCells === 0, `no intervals in the data, none shown (${got.intervalCells})`);
  }
  check(!/headway/i.test(got.headers) && /time gap/.test(got.headers), 'the summary calls the headway a time gap');
  check(got.bars.speed === got.speedCI && got.bars.incidents === got.incidentsCI,
    `the mean speed and incidents charts have an error bar per interval (${got.bars.speed} of ${got.speedCI}, ${got.bars.incidents} of ${got.incidentsCI})`);
  check(got.faultChart === got.fault > 0 && got.bars.fault === got.faultCI,
    `the at-fault collisions chart is drawn when the data has them (${got.faultChart}, ${got.fault} rows, ${got.bars.fault} error bars of ${got.faultCI})`);
  check(got.precisionShown === (got.precision > 0 ? got.rows : 0), `the precision table has a row per group when the data has precision (${got.precisionShown})`);
  check(got.notes.filter((n) => /too few seeds/.test(n)).length === got.fewSeeds && got.notes.join('\n').split('⚠').length - 1 === got.warnings,
    `each row's notes (no intervals: ${got.fewSeeds}, warnings: ${got.warnings}) are shown under it (${got.notes.length} note lines)`);
  if (got.pairs > 0) {
    console.log(`  pairs: ${got.pairText}`);
    check(got.pairsShown === got.pairs, `the paired comparisons table has a row per pair (${got.pairsShown} of ${got.pairs})`);
    const known = got.verdicts.every((v) => ['better', 'worse', 'no difference', 'too few seeds', '–'].includes(v.text)
      && v.cls === (v.text === 'better' || v.text === 'worse' ? `verdict ${v.text}` : 'verdict'));
    check(got.verdicts.length > 0 && known, `the verdicts are shown, better and worse coloured (${[...new Set(got.verdicts.map((v) => v.text))].join(', ')})`);
    if (got.verdictsObject) check(/^Verdicts: Holm over \d+ tests, 5% family-wise; paired t-test.* for speed, exact sign-flip.* for rates; no verdict below 8 seeds/.test(got.method), `the page says how the verdicts were reached (${got.method})`);
    else check(/before the tests/.test(got.method), `a bench from before the tests says how its verdicts were reached (${got.method})`);
    const m = await testMatrices(page);
    if (expect === 'today' || expect === 'many') check(['better', 'worse', 'no difference', 'too few seeds'].every((v) => m.seen.includes(v)), `the matrices show every verdict (${m.seen.join(', ')})`);
  } else {
    check(got.pairsShown === 0, 'no pairs in the data, no paired table');
  }
  await testScatterAndLabels(page, expect);
  if (expect === 'today') {
    check(got.speedCI === got.rows && got.pairs > 0 && got.precision > 0 && got.fault > 0, 'the data of today\'s bench has intervals, pairs, precision and at-fault rates');
    check(got.verdicts.some((v) => v.text === 'better') && got.verdicts.some((v) => v.text === 'worse') && got.verdicts.some((v) => v.text === 'no difference')
      && got.verdicts.some((v) => v.text === 'too few seeds'), 'its pairs have each verdict');
    check(got.oneSidedCells >= 2, `a rate with no event shows its one-sided bound, "0.00 (≤ …)" (${got.oneSidedCells} cells)`);
    check(got.collisionsNote === '', 'its collisions are contacts: no note on them');
  } else if (expect === 'before-contacts') {
    check(got.oneSidedCells === 0 && got.intervalCells > 0, `an older bench's zero-event intervals stay two-sided (${got.oneSidedCells} "≤" cells)`);
    check(/counted for every second of contact/.test(got.collisionsNote), `its collisions are said to predate contacts (${got.collisionsNote})`);
  } else if (expect === 'older') {
    check(got.speedCI === 0 && got.pairs === 0 && got.precision === 0 && got.fault === 0, 'the older data has no interval, pair, precision or at-fault rate');
    check(/–/.test(got.summaryText), 'the older data\'s missing figures are dashes');
  } else if (expect === 'no-summary') {
    check(got.rows > 0 && got.speedCI === 0, `the page summarizes the runs itself, without intervals (${got.rows} rows)`);
  }
}

async function testReport(context, path, artifacts, opts = {}) {
  console.log(`report${opts.name ? ` (${opts.name})` : ''}: ${path}`);
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
      summaryRows: document.querySelectorAll('#summary tbody tr:not(.notes-row)').length,
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
  await testReportFigures(page, opts.expect);
  check(errors.length === 0, `no console errors${errors.length ? `: ${errors.join(' | ')}` : ''}`);
  check(requests.length === 0, `no network requests${requests.length ? `: ${requests.join(', ')}` : ''}`);
  const shot = join(artifacts, opts.name ? `report-${opts.name}.png` : 'report.png');
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
    const cut = await page.evaluate(() => {
      const b = document.getElementById('btn-cut');
      return b ? (b.hidden ? 'hidden' : 'shown') : 'absent';
    });
    check(cut !== 'shown', `the live view offers no cut command (its button: ${cut})`);
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
  const template = args.viewer ? readFileSync(args.viewer, 'utf8') : null;
  const page = (otr, html) => {
    if (template) writeFileSync(html, fillViewer(template, readFileSync(otr)));
    else run(bin, ['view', otr, '--html', html, '--quiet']);
  };
  const drives = [
    { name: 'incident', incident: true, collision: 'ego hit car ahead (at fault)',
      flags: ['--scenario', join(args.sourceDir, 'tests/scenarios/hard_brake_ahead.json'), '--policy', 'walkthrough'] },
    { name: 'clean', incident: false, flags: ['--policy', 'reference', '--seed', '1'] },
  ];
  for (const d of drives) {
    const otr = join(w, `${d.name}.otr`);
    const html = join(w, `${d.name}.html`);
    rmSync(otr, { force: true });
    rmSync(html, { force: true });
    run(bin, ['drive', ...d.flags, '--minutes', '0.5', '--record', otr, '--quiet']);
    page(otr, html);
    args.pages.push({ page: html, replay: otr, incident: d.incident, collision: d.collision, name: d.name });
  }
  // a scenario cut from a recorded run, driven: its replay says where it was cut from, and
  // its frames keep the run's clock (from t 25 s)
  const source = join(w, 'cut-source.otr');
  const scenario = join(w, 'cut.json');
  const cut = join(w, 'cut.otr');
  for (const f of [source, scenario, cut, join(w, 'cut.html')]) rmSync(f, { force: true });
  run(bin, ['drive', '--policy', 'reference', '--seed', '3', '--minutes', '1', '--record', source, '--quiet']);
  run(bin, ['cut', source, '--at', '40', '-o', scenario, '--quiet']);
  run(bin, ['drive', '--scenario', scenario, '--record', cut, '--quiet']);
  page(cut, join(w, 'cut.html'));
  args.pages.push({ page: join(w, 'cut.html'), replay: cut, incident: false, cut: true, name: 'cut' });
  // the contact replays of test/encode.mjs, read by the C++ side too (its reader checks the
  // contact numbers) when it writes their pages
  for (const d of contactDrives()) {
    const otr = join(w, `${d.name}.otr`);
    const html = join(w, `${d.name}.html`);
    writeFileSync(otr, d.drive.bytes);
    rmSync(html, { force: true });
    page(otr, html);
    args.pages.push({ page: html, replay: otr, incident: d.incident, collision: d.collision, name: d.name });
  }
  const bench = join(w, 'bench');
  rmSync(bench, { recursive: true, force: true });
  run(bin, ['bench', '--policies', 'walkthrough,reference', '--seeds', '1-2', '--minutes', '0.5', '--traffic', 'faithful',
    '--jobs', '1', '--record-worst', '1', '--out', bench, '--html', join(bench, 'report.html'), '--quiet']);
  args.report = join(bench, 'report.html');
  args.reportLinksExist = true;
}

// Replays made by test/encode.mjs with contacts: a contact of three seconds (the rubric's
// latched incident each second), a jerk, an at-fault contact; and one as a writer from before
// contacts wrote it (20-byte incidents, collisions counted per second).
function contactDrives() {
  return [
    { name: 'synthetic-incidents', incident: true, collision: 'Collision with car 4 (contact 1) — hit from behind (not at fault)',
      drive: syntheticDrive({ seconds: 30, incidents: [{ step: 400, type: 'collision', value: 4, kind: 'hit_from_behind' },
        { step: 450, type: 'collision', value: 4, kind: 'hit_from_behind' }, { step: 500, type: 'collision', value: 4, kind: 'hit_from_behind' },
        { step: 900, type: 'max_jerk', value: 14.2 }, { step: 1200, type: 'collision', value: 6, kind: 'ego_lane_change', atFault: true }] }) },
    { name: 'synthetic-before-contacts', incident: true, collision: 'Collision with car 4 — hit from behind (not at fault)',
      drive: syntheticDrive({ seconds: 20, preContacts: true, incidents: [{ step: 300, type: 'collision', value: 4, kind: 'hit_from_behind' },
        { step: 350, type: 'collision', value: 4, kind: 'hit_from_behind' }] }) },
  ];
}

async function main() {
  const args = parseArgs(process.argv.slice(2));
  mkdirSync(args.artifacts, { recursive: true });
  if (args.overtake) recordWithOvertake(args);
  if (args.synthetic) {
    if (!args.viewer) throw new Error('--synthetic needs --viewer viewer.html');
    const template = readFileSync(args.viewer, 'utf8');
    const drives = [
      ...contactDrives(),
      { name: 'synthetic-clean', incident: false, drive: syntheticDrive({ seconds: 20 }) },
      { name: 'synthetic-legacy', incident: true, drive: syntheticDrive({ seconds: 20, legacy: true, incidents: [{ step: 300, type: 'collision', value: 2 }] }) },
      // a cut scenario's replay: checkpoints among the records, frames from t 1049.44 s, the
      // moment at t 1064.44 s, and the file's name in the page's config
      { name: 'synthetic-cut', incident: true, cut: true, fileName: 'synthetic-cut.otr', collision: 'hit from behind (not at fault)',
        drive: syntheticDrive({ seconds: 20, startStep: 52472, checkpointEvery: 250,
          incidents: [{ step: 53222, type: 'collision', value: 3, kind: 'hit_from_behind' }],
          cutFrom: { scenario: 'reference, faithful traffic, seed 5, t 1064.4 s', replay: 't2s5.otr', policy: 'reference', traffic: 'faithful', seed: 5,
            at_s: 1064.44, start_s: 1049.44, incident: 'collision hit_from_behind (not at fault) at t 1064.44 s' } }) },
    ];
    for (const d of drives) {
      const replayPath = join(args.artifacts, `${d.name}.otr`);
      const pagePath = join(args.artifacts, `${d.name}.html`);
      writeFileSync(replayPath, d.drive.bytes);
      writeFileSync(pagePath, fillViewer(template, d.drive.bytes, d.fileName));
      args.pages.push({ page: pagePath, replay: replayPath, incident: d.incident, collision: d.collision, name: d.name, cut: d.cut, fileName: d.fileName });
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
    if (args.report) {
      await testReport(context, args.report, args.artifacts, { linksExist: args.reportLinksExist });
      for (const v of reportVariants(args.report)) await testReport(context, v.path, args.artifacts, { name: v.name, expect: v.expect });
    }
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
