// The replay viewer: loads a replay (embedded in the page, from the server, or live over a
// websocket), then drives the view, HUD, timeline and charts from one playhead.
import './viewer.css';

import { base64ToBytes, decodeReplayAsync, parseHeader, Replay, ReplayError } from '../replay.js';
import { Charts } from './charts.js';
import {
  clock, cutCommand, cutOriginText, incidentText, latchedText, METRES_PER_MILE, MPH_PER_MPS, planStatusText, safetyStatusText,
  safetyThresholds,
} from './format.js';
import { Scene } from './scene.js';

// Spelt in parts (joined at run time, so the minifier cannot fold them) so that the C++
// side's replacement never touches the code.
const CONFIG_PLACEHOLDER = ['__OVERTAKE', 'CONFIG__'].join('_');
const DATA_PLACEHOLDER = ['__OVERTAKE', 'DATA__'].join('_');

const SPEEDS = [0.25, 0.5, 1, 2, 4, 8, 16];
const BANNER_S = 3; // an incident's banner stays this long (simulated seconds)
const MAX_BANNERS = 4;
const MARKER_BUCKETS = 400; // at most one timeline marker per type per 1/400 of the run
const LIVE_REFRESH_MS = 500;

const $ = (id) => document.getElementById(id);

// The step of the moment a cut scenario's replay was cut around.
const cutStep = (r) => Math.round(r.cutFrom.atS / r.stepS);

class Viewer {
  constructor() {
    this.root = $('viewer');
    this.canvas = $('road');
    this.replay = null;
    this.scene = new Scene(this.canvas, null);
    this.charts = null;
    this.frame = 0;
    this.simT = 0;
    this.playing = false;
    this.speed = 1;
    this.live = false;
    this.following = false;
    this.rafPending = false;
    this.lastTick = 0;
    this.lastLiveRefresh = 0;
    this.liveDirty = false;
    this.markerCount = -1;
    this.fileName = null; // the replay file's name, for the cut command (null: not known)
    this.cutText = '';
    this.hud = {
      speed: $('hud-speed'), accTotal: $('hud-acc-total'), accTan: $('hud-acc-tan'), accNorm: $('hud-acc-norm'),
      jerk: $('hud-jerk'), distance: $('hud-distance'), best: $('hud-best'), timer: $('hud-timer'),
      lane: $('hud-lane'), d: $('hud-d'), ttc: $('hud-ttc'), ttcEntering: $('hud-ttc-entering'), headway: $('hud-headway'),
    };
    this.thresholds = safetyThresholds(null);
    this.bannerKey = '';
    this.timing = {}; // milliseconds: base64Ms, decodeMs, showMs, readyMs (since navigation start)
    this._wire();
  }

  // ---- loading ------------------------------------------------------------------------------

  /// Shows a decoded replay (replacing any other).
  show(replay) {
    this.replay = replay;
    this.thresholds = safetyThresholds(replay.report);
    this.scene.setReplay(replay);
    if (!this.charts) this.charts = new Charts($('charts'), replay, (t) => this.seekTime(t, true));
    else this.charts.setReplay(replay);
    // a cut scenario's replay starts later than 0 (it keeps the run's clock)
    const duration = replay.frames ? replay.time[replay.frames - 1] - replay.time[0] : 0;
    const defaultWindow = duration > 180 ? '120' : '0';
    $('chart-window').value = defaultWindow;
    this.charts.setWindow(Number(defaultWindow));
    this.frame = 0;
    this.simT = replay.frames ? replay.time[0] : 0;
    this.markerCount = -1;
    $('btn-cut').hidden = this.live;
    if (this.live) this._showCut(false);
    this.cutText = '';
    this._provenance();
    this._cutOrigin();
    this._timeline();
    this.root.dataset.frames = String(replay.frames);
    this.scene.resize();
    this.charts.resize();
    this.render();
  }

  /// Decodes file bytes and shows them; problems go to the banner. `file` is the replay
  /// file's name when the page knows it (for the cut command; null: a placeholder). Resolves
  /// to the replay, or null when nothing could be read.
  async load(bytes, name, file = null) {
    let replay;
    const t0 = performance.now();
    try {
      replay = await decodeReplayAsync(bytes, name);
      this.timing.decodeMs = performance.now() - t0;
    } catch (e) {
      this.fail(e instanceof ReplayError ? e.message : `${name}: ${e.message || e}`);
      return null;
    }
    this.live = false;
    $('btn-live').hidden = true;
    if (replay.problem) {
      this.banner(`${replay.problem}.\nShowing what could be read: ${replay.summary()}.`, 'warn');
    } else {
      this.banner(null);
    }
    if (replay.frames === 0) {
      this.root.dataset.state = 'error';
      this.banner(`${replay.problem || `${name} holds no frames`}.\nNothing could be read.`, 'error');
      $('status').textContent = 'no frames';
      return replay;
    }
    const t1 = performance.now();
    this.fileName = file;
    this.show(replay);
    this.timing.showMs = performance.now() - t1;
    this.root.dataset.state = replay.problem ? 'partial' : 'ready';
    return replay;
  }

  fail(message) {
    this.root.dataset.state = 'error';
    this.banner(message, 'error');
    $('status').textContent = 'could not read the replay';
  }

  banner(text, level = 'error') {
    const el = $('error-banner');
    if (!text) {
      el.hidden = true;
      el.textContent = '';
      return;
    }
    el.hidden = false;
    el.className = level === 'warn' ? 'warn' : '';
    el.dataset.level = level;
    el.textContent = text;
  }

  /// Live: the header arrives first, then records.
  startLive(url) {
    this.live = true;
    this.root.dataset.state = 'loading';
    $('status').textContent = 'connecting…';
    const wsUrl = new URL(url, window.location.href);
    wsUrl.protocol = wsUrl.protocol === 'https:' ? 'wss:' : 'ws:';
    let ws;
    try {
      ws = new WebSocket(wsUrl.href);
    } catch (e) {
      this.fail(`cannot open the live stream ${wsUrl.href}: ${e.message}`);
      return;
    }
    ws.binaryType = 'arraybuffer';
    let replay = null;
    ws.onmessage = (ev) => {
      if (typeof ev.data === 'string') {
        try {
          replay = new Replay(parseHeader(ev.data));
        } catch (e) {
          this.fail(`live stream: ${e.message}`);
          ws.close();
          return;
        }
        this.following = true;
        $('btn-live').hidden = false;
        this.show(replay);
        this.root.dataset.state = 'live';
        $('status').textContent = 'live';
        return;
      }
      if (!replay) {
        this.fail('live stream: records arrived before the header');
        ws.close();
        return;
      }
      replay.appendRecords(new Uint8Array(ev.data), { live: true });
      if (replay.problem) {
        this.banner(`live stream: ${replay.problem}`, 'warn');
      }
      this.liveDirty = true;
      this.requestRender();
    };
    ws.onerror = () => {
      if (!replay) this.fail(`cannot connect to the live stream at ${wsUrl.href}`);
    };
    ws.onclose = () => {
      if (!replay) return;
      this.live = false;
      this.following = false;
      $('btn-live').hidden = true;
      this.liveDirty = true;
      $('status').textContent = replay.ended ? 'live run finished' : 'live stream closed';
      if (replay.ended) this._reportStatus(replay);
      this.root.dataset.state = replay.ended ? 'ready' : 'partial';
      if (!replay.ended && !replay.problem) this.banner('The live stream closed before the run ended.', 'warn');
      this.requestRender();
    };
  }

  _provenance() {
    const r = this.replay;
    const p = (r.header && r.header.provenance) || {};
    const parts = [];
    if (p.policy) parts.push(`policy ${p.policy}`);
    if (p.traffic) parts.push(`${p.traffic} traffic`);
    if (p.seed !== undefined) parts.push(`seed ${p.seed}`);
    if (p.track) parts.push(`track ${p.track}`);
    if (p.scenario) parts.push(`scenario ${p.scenario}`);
    $('provenance').textContent = parts.join(' · ');
    const end = r.frames ? r.time[r.frames - 1] : 0;
    // a cut scenario's replay keeps the run's clock: its frames start later than 0
    const span = r.frames && r.step[0] > 0 ? `${clock(r.time[0])}–${clock(end)}` : clock(end);
    $('status').textContent = `${r.frames.toLocaleString('en')} steps · ${span} · ${r.incidents} incident${r.incidents === 1 ? '' : 's'}`;
    this._reportStatus(r);
  }

  // What the run's report adds: collisions at fault and near misses, and how the planner
  // planned when it left normal planning (the report's plan statuses).
  _reportStatus(r) {
    const status = $('status');
    const safety = safetyStatusText(r.report);
    if (safety) status.textContent += ` · ${safety}`;
    this.thresholds = safetyThresholds(r.report);
    const text = planStatusText(r.report);
    if (!text) return;
    status.textContent += ` · ${text}`;
    const first = r.report.plan_status.first_reason;
    if (first) status.title = `first: ${first}`;
  }

  // Where a cut scenario's replay was cut from: the bar under the header (hidden for another).
  _cutOrigin() {
    const c = this.replay.cutFrom;
    const bar = $('cut-origin');
    bar.hidden = !c;
    if (!c) return;
    bar.dataset.atS = String(c.atS);
    bar.title = c.scenario ? `scenario: ${c.scenario}${Number.isFinite(c.startS) ? `, from t ${c.startS.toFixed(2)} s` : ''}` : '';
    $('cut-origin-text').textContent = cutOriginText(c);
    $('cut-origin-seek').textContent = `go to t ${c.atS.toFixed(2)} s`;
  }

  // ---- the timeline -------------------------------------------------------------------------

  _timeline() {
    const r = this.replay;
    const scrub = $('scrubber');
    scrub.max = String(Math.max(0, r.frames - 1));
    this._cutMark();
    if (this.markerCount === r.incidents) return;
    this.markerCount = r.incidents;
    const box = $('incident-markers');
    box.textContent = '';
    if (r.frames === 0) return;
    const s0 = r.step[0];
    const span = Math.max(1, r.step[r.frames - 1] - s0);
    const buckets = new Map();
    // a collision is a contact, marked once, at its first incident; the rubric's latched
    // incidents of the same contact (one per second of it) get lighter marks of their own
    const { byNumber, repeat } = r.contacts();
    const nth = new Map(); // contact -> incidents of it so far
    for (let k = 0; k < r.incidents; ++k) {
      const step = r.step[r.incFrame[k]];
      const type = r.incidentTypeName(r.incType[k]);
      const cls = r.incidentClass(k);
      const contact = r.incidentContact(k);
      const latched = repeat[k] === 1;
      if (contact >= 0) nth.set(contact, (nth.get(contact) || 0) + 1);
      // collisions at fault and not at fault get marks of their own (filled, outlined)
      const fault = cls ? String(cls.atFault) : '';
      const key = `${type}:${fault}:${latched ? `latched ${contact}` : ''}:${Math.round(((step - s0) / span) * MARKER_BUCKETS)}`;
      const b = buckets.get(key);
      if (b) b.count += 1;
      else {
        const of = contact >= 0 ? byNumber.get(contact).incidents : 0;
        buckets.set(key, { k, step, type, cls, contact, latched, nth: nth.get(contact) || 0, of, count: 1 });
      }
    }
    const frag = document.createDocumentFragment();
    for (const b of buckets.values()) {
      const m = document.createElement('button');
      m.type = 'button';
      m.className = b.latched ? 'marker latched' : 'marker';
      m.dataset.step = String(b.step);
      m.dataset.type = b.type;
      m.dataset.count = String(b.count);
      if (b.cls) {
        m.dataset.kind = b.cls.kind;
        m.dataset.atFault = String(b.cls.atFault);
      }
      if (b.contact >= 0) m.dataset.contact = String(b.contact + 1);
      if (b.latched) m.dataset.latched = 'true';
      m.style.left = `${(((b.step - s0) / span) * 100).toFixed(3)}%`;
      let text = incidentText(b.type, r.incValue[b.k], b.cls, b.contact);
      if (b.latched) text += ` — ${latchedText(b.nth, b.of)}`;
      else if (b.of > 1) text += ` — the rubric counted ${b.of} collision incidents for it (one per second of contact)`;
      const more = b.count > 1 ? ` (and ${b.count - 1} more nearby)` : '';
      m.title = `${clock(b.step * r.stepS)} ${text}${more}`;
      m.setAttribute('aria-label', m.title);
      frag.appendChild(m);
    }
    box.appendChild(frag);
  }

  // The moment a cut scenario was cut around, as a line on the timeline (none when the replay
  // was not cut, or the moment is outside its frames).
  _cutMark() {
    const r = this.replay;
    const c = r.cutFrom;
    const mark = $('cut-mark');
    const step = c && r.frames ? cutStep(r) : -1;
    if (step < 0 || step < r.step[0] || step > r.step[r.frames - 1]) {
      mark.hidden = true;
      return;
    }
    const s0 = r.step[0];
    const span = Math.max(1, r.step[r.frames - 1] - s0);
    mark.hidden = false;
    mark.dataset.step = String(step);
    mark.style.left = `${(((step - s0) / span) * 100).toFixed(3)}%`;
  }

  // ---- the cut command ----------------------------------------------------------------------

  _showCut(show) {
    $('cut-box').hidden = !show;
    $('btn-cut').setAttribute('aria-expanded', String(show));
    $('cut-copy-status').textContent = '';
    if (show && this.replay && this.replay.frames) this._cut(Math.min(this.frame, this.replay.frames - 1));
  }

  // The command that cuts a scenario around frame i, while the box shows it.
  _cut(i) {
    if ($('cut-box').hidden) return;
    const text = cutCommand(this.fileName, this.replay.time[i], $('cut-traffic').value);
    if (text === this.cutText) return;
    this.cutText = text;
    $('cut-command').textContent = text;
    $('cut-copy-status').textContent = '';
  }

  // Copies the command (the clipboard API where the page may use it), else selects it for
  // the user to copy.
  _copyCut() {
    const el = $('cut-command');
    const status = $('cut-copy-status');
    const select = () => {
      const sel = window.getSelection();
      if (sel) sel.selectAllChildren(el);
      status.textContent = 'selected: press Ctrl+C to copy';
    };
    const clip = navigator.clipboard;
    if (!clip || typeof clip.writeText !== 'function') {
      select();
      return;
    }
    clip.writeText(el.textContent).then(() => {
      status.textContent = 'copied';
    }, select);
  }

  // ---- playback -----------------------------------------------------------------------------

  /// Moves to world step `step` (the nearest recorded one at or before it) and draws it now.
  seek(step) {
    if (!this.replay || this.replay.frames === 0) return;
    this.following = false;
    this.frame = this.replay.frameOfStep(Math.round(step));
    this.simT = this.replay.time[this.frame];
    this.render();
  }

  /// Moves to time `t` (seconds).
  seekTime(t, pause = false) {
    if (!this.replay) return;
    if (pause) this.pause();
    this.seek(Math.floor(t / this.replay.stepS + 1e-9));
  }

  /// Steps `n` frames forward (or back when negative), paused.
  stepBy(n) {
    if (!this.replay || this.replay.frames === 0) return;
    this.pause();
    const i = Math.min(this.replay.frames - 1, Math.max(0, this.frame + n));
    this.seek(this.replay.step[i]);
  }

  play() {
    if (!this.replay || this.replay.frames === 0) return;
    if (!this.live && this.frame >= this.replay.frames - 1) this.seek(this.replay.step[0]);
    this.playing = true;
    this.lastTick = 0;
    this._buttons();
    this.requestRender();
  }

  pause() {
    this.playing = false;
    this.following = false;
    this._buttons();
  }

  setSpeed(x) {
    if (!SPEEDS.includes(Number(x))) throw new Error(`speed must be one of ${SPEEDS.join(', ')}`);
    this.speed = Number(x);
    for (const b of document.querySelectorAll('#speeds button')) {
      b.setAttribute('aria-pressed', String(Number(b.dataset.speed) === this.speed));
    }
  }

  follow() {
    this.following = true;
    this.playing = false;
    this._buttons();
    this.requestRender();
  }

  _buttons() {
    const play = $('btn-play');
    play.textContent = this.playing ? '❚❚ pause' : '▶ play';
    play.setAttribute('aria-pressed', String(this.playing));
    this.root.dataset.playing = String(this.playing);
    $('btn-live').setAttribute('aria-pressed', String(this.following));
  }

  requestRender() {
    if (this.rafPending) return;
    this.rafPending = true;
    requestAnimationFrame((ts) => this._tick(ts));
  }

  _tick(ts) {
    this.rafPending = false;
    const r = this.replay;
    if (!r) return;
    if (this.liveDirty) {
      const now = performance.now();
      if (now - this.lastLiveRefresh > LIVE_REFRESH_MS || !this.live) {
        this.liveDirty = false;
        this.lastLiveRefresh = now;
        this.root.dataset.frames = String(r.frames);
        this.charts.refresh();
        this._timeline();
        this._provenance();
        if (this.live) $('status').textContent += ' · live';
      }
    }
    if (this.following && r.frames > 0) {
      this.frame = r.frames - 1;
      this.simT = r.time[this.frame];
    } else if (this.playing && r.frames > 0) {
      if (this.lastTick) {
        const dt = Math.min(0.25, (ts - this.lastTick) / 1000);
        this.simT += dt * this.speed;
      }
      this.lastTick = ts;
      const last = r.frames - 1;
      if (this.simT >= r.time[last]) {
        this.simT = r.time[last];
        if (!this.live) {
          this.playing = false;
          this._buttons();
        }
      }
      this.frame = r.frameOfStep(Math.floor(this.simT / r.stepS + 1e-9));
    }
    this.render();
    if (this.playing || this.following || this.liveDirty) this.requestRender();
  }

  // ---- drawing ------------------------------------------------------------------------------

  render() {
    const r = this.replay;
    if (!r || r.frames === 0) {
      this.scene.draw(0);
      return;
    }
    const i = Math.min(this.frame, r.frames - 1);
    const t = r.time[i];
    this._banners(i, t);
    this.scene.draw(i);
    this._hud(i, t);
    $('scrubber').value = String(i);
    $('time-label').textContent = `${clock(t)} / ${clock(r.time[r.frames - 1])} · step ${r.step[i]}`;
    this._cut(i);
    this.root.dataset.step = String(r.step[i]);
    this.root.dataset.frame = String(i);
    this.root.dataset.frames = String(r.frames);
    this.charts.setTime(t);
  }

  _hud(i, t) {
    const r = this.replay;
    const lim = r.limits;
    const h = this.hud;
    const set = (el, text, over) => {
      if (el.textContent !== text) el.textContent = text;
      el.classList.toggle('over-limit', Boolean(over));
    };
    const mph = r.egoSpeed[i] * MPH_PER_MPS;
    set(h.speed, mph.toFixed(2), lim.speed_mps && r.egoSpeed[i] > lim.speed_mps);
    h.speed.dataset.mps = String(r.egoSpeed[i]);
    set(h.accTotal, r.accTotal[i].toFixed(2), lim.acceleration_mps2 && r.accTotal[i] > lim.acceleration_mps2);
    set(h.accTan, r.accT[i].toFixed(2), false);
    set(h.accNorm, r.accN[i].toFixed(2), false);
    set(h.jerk, r.jerk[i].toFixed(2), lim.jerk_mps3 && Math.abs(r.jerk[i]) > lim.jerk_mps3);
    set(h.distance, (r.distanceSince[i] / METRES_PER_MILE).toFixed(2), false);
    set(h.best, (r.bestFree[i] / METRES_PER_MILE).toFixed(2), false);
    set(h.timer, clock(t), false);
    const road = r.header.road || {};
    const width = road.lane_width_m || 4;
    const lanes = road.lanes || 3;
    const d = r.egoD[i];
    const lane = Math.floor(d / width);
    set(h.lane, lane >= 0 && lane < lanes ? String(lane) : 'off', !(lane >= 0 && lane < lanes));
    set(h.d, d.toFixed(2), false);
    // near misses: below the threshold in red; none is a dash
    const th = this.thresholds;
    const secs = (el, v, limit) => set(el, Number.isFinite(v) ? v.toFixed(2) : '–', Number.isFinite(v) && v < limit);
    secs(h.ttc, r.ttcAhead[i], th.ttc);
    secs(h.ttcEntering, r.ttcEntering[i], th.ttc);
    secs(h.headway, r.headway[i], th.headway);
  }

  _banners(i, t) {
    const r = this.replay;
    // incidents are in frame order: find those of the last BANNER_S seconds
    const from = r.frameOfStep(Math.ceil((t - BANNER_S) / r.stepS));
    let hi = r.incidents;
    let lo = 0;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (r.incFrame[mid] <= i) lo = mid + 1;
      else hi = mid;
    }
    const end = lo; // first incident after frame i
    const shown = [];
    const hits = new Set();
    const contacts = new Set(); // a contact's banner once, however many latched incidents it has
    for (let k = end - 1; k >= 0 && r.incFrame[k] >= from && shown.length < MAX_BANNERS; --k) {
      const type = r.incidentTypeName(r.incType[k]);
      const cls = r.incidentClass(k);
      const contact = r.incidentContact(k);
      if (type === 'collision') hits.add(Math.round(r.incValue[k]));
      if (contact >= 0) {
        if (contacts.has(contact)) continue;
        contacts.add(contact);
      }
      shown.push({ k, type, cls, contact, text: incidentText(type, r.incValue[k], cls, contact) });
    }
    this.scene.highlightCars = hits;
    const key = shown.map((s) => s.k).join(',');
    if (key === this.bannerKey) return;
    this.bannerKey = key;
    const box = $('incident-banners');
    box.textContent = '';
    for (const s of shown) {
      const b = document.createElement('div');
      b.className = 'banner';
      b.dataset.type = s.type;
      if (s.cls) b.dataset.atFault = String(s.cls.atFault);
      if (s.contact >= 0) b.dataset.contact = String(s.contact + 1);
      b.textContent = s.text;
      box.appendChild(b);
    }
  }

  // ---- input --------------------------------------------------------------------------------

  _wire() {
    $('btn-play').addEventListener('click', () => (this.playing ? this.pause() : this.play()));
    $('btn-step-back').addEventListener('click', () => this.stepBy(-1));
    $('btn-step-fwd').addEventListener('click', () => this.stepBy(1));
    $('btn-live').addEventListener('click', () => this.follow());
    $('btn-cut').addEventListener('click', () => this._showCut($('cut-box').hidden));
    $('btn-cut-copy').addEventListener('click', () => this._copyCut());
    $('cut-traffic').addEventListener('change', () => {
      if (this.replay && this.replay.frames) this._cut(Math.min(this.frame, this.replay.frames - 1));
    });
    $('cut-origin-seek').addEventListener('click', () => {
      if (!this.replay || !this.replay.cutFrom) return;
      this.pause();
      this.seek(cutStep(this.replay));
    });
    for (const b of document.querySelectorAll('#speeds button')) {
      b.addEventListener('click', () => this.setSpeed(Number(b.dataset.speed)));
    }
    $('scrubber').addEventListener('input', (e) => {
      if (!this.replay) return;
      const i = Number(e.target.value);
      this.seek(this.replay.step[Math.min(i, this.replay.frames - 1)]);
    });
    $('incident-markers').addEventListener('click', (e) => {
      const m = e.target.closest('.marker');
      if (!m) return;
      this.pause();
      this.seek(Number(m.dataset.step));
    });
    $('chart-window').addEventListener('change', (e) => {
      if (!this.charts) return;
      this.charts.setWindow(Number(e.target.value));
      this.render();
    });
    $('opt-heading-up').addEventListener('change', (e) => {
      this.scene.headingUp = e.target.checked;
      this.scene.recenter();
      this.render();
    });
    $('opt-labels').addEventListener('change', (e) => {
      this.scene.labels = e.target.checked;
      this.render();
    });
    $('btn-recenter').addEventListener('click', () => {
      this.scene.recenter();
      this.render();
    });

    const canvas = this.canvas;
    canvas.addEventListener('wheel', (e) => {
      e.preventDefault();
      const factor = Math.exp(-e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015));
      this.scene.zoomAt(factor, e.offsetX, e.offsetY);
      this.render();
    }, { passive: false });
    let drag = null;
    canvas.addEventListener('pointerdown', (e) => {
      drag = { x: e.clientX, y: e.clientY, id: e.pointerId };
      canvas.setPointerCapture(e.pointerId);
      canvas.classList.add('dragging');
    });
    canvas.addEventListener('pointermove', (e) => {
      if (!drag || e.pointerId !== drag.id) return;
      this.scene.panX += e.clientX - drag.x;
      this.scene.panY += e.clientY - drag.y;
      drag.x = e.clientX;
      drag.y = e.clientY;
      this.render();
    });
    const endDrag = () => {
      drag = null;
      canvas.classList.remove('dragging');
    };
    canvas.addEventListener('pointerup', endDrag);
    canvas.addEventListener('pointercancel', endDrag);
    canvas.addEventListener('dblclick', () => {
      this.scene.recenter();
      this.render();
    });

    window.addEventListener('keydown', (e) => {
      const tag = e.target && e.target.tagName;
      if (tag === 'INPUT' || tag === 'SELECT' || tag === 'TEXTAREA') return;
      if (e.key === ' ') {
        e.preventDefault();
        if (tag === 'BUTTON') e.target.blur(); // no click on key-up as well
        if (this.playing) this.pause();
        else this.play();
      } else if (e.key === 'ArrowRight') {
        e.preventDefault();
        this.stepBy(e.shiftKey ? 50 : 1);
      } else if (e.key === 'ArrowLeft') {
        e.preventDefault();
        this.stepBy(e.shiftKey ? -50 : -1);
      }
    });

    const resize = () => {
      this.scene.resize();
      if (this.charts) this.charts.resize();
      this.render();
    };
    new ResizeObserver(resize).observe($('stage'));
    window.addEventListener('resize', resize);

    // a replay file can be opened or dropped on the page
    $('file-input').addEventListener('change', (e) => {
      const f = e.target.files && e.target.files[0];
      if (f) this._openFile(f);
    });
    const hint = $('drop-hint');
    window.addEventListener('dragover', (e) => {
      e.preventDefault();
      hint.hidden = false;
    });
    window.addEventListener('dragleave', (e) => {
      if (e.relatedTarget === null) hint.hidden = true;
    });
    window.addEventListener('drop', (e) => {
      e.preventDefault();
      hint.hidden = true;
      const f = e.dataTransfer && e.dataTransfer.files && e.dataTransfer.files[0];
      if (f) this._openFile(f);
    });
  }

  _openFile(file) {
    this.pause();
    file.arrayBuffer().then(
      (buf) => this.load(new Uint8Array(buf), file.name, file.name),
      (e) => this.fail(`${file.name}: cannot read the file (${e.message})`),
    );
  }
}

function readConfig() {
  const el = $('overtake-config');
  const text = el ? el.textContent.trim() : '';
  if (!text || text === CONFIG_PLACEHOLDER) return null;
  return JSON.parse(text);
}

function embeddedBytes() {
  const el = $('overtake-data');
  const text = el ? el.textContent.trim() : '';
  if (!text || text === DATA_PLACEHOLDER) return null;
  return base64ToBytes(text);
}

// The replay file's name, when the page's config gives it (`name`); else null.
function fileName(config) {
  const name = config && config.name;
  return typeof name === 'string' && name.trim() ? name : null;
}

function start(viewer) {
  let config;
  try {
    config = readConfig();
  } catch (e) {
    viewer.fail(`the page's configuration is not JSON (${e.message})`);
    return Promise.resolve();
  }
  const source = config ? config.source : embeddedBytes() ? 'embedded' : null;
  if (!source) {
    viewer.root.dataset.state = 'empty';
    $('status').textContent = 'no replay in this page: open or drop a replay file (overtake view FILE --html OUT writes a page with one)';
    $('open-file').hidden = false;
    return Promise.resolve();
  }
  if (source === 'embedded') {
    let bytes;
    const t0 = performance.now();
    try {
      bytes = embeddedBytes();
    } catch (e) {
      viewer.fail(`the replay in this page is not valid base64 (${e.message})`);
      return Promise.resolve();
    }
    if (!bytes) {
      viewer.fail('this page should hold a replay, but its data element is empty');
      return Promise.resolve();
    }
    viewer.timing.base64Ms = performance.now() - t0;
    return viewer.load(bytes, (config && config.name) || 'the embedded replay', fileName(config));
  }
  if (source === 'http') {
    const url = config.url || '/replay.otr';
    return fetch(url)
      .then((res) => {
        if (!res.ok) throw new Error(`HTTP ${res.status} ${res.statusText}`);
        return res.arrayBuffer();
      })
      .then(
        (buf) => viewer.load(new Uint8Array(buf), (config && config.name) || url, fileName(config)),
        (e) => viewer.fail(`cannot fetch the replay from ${url}: ${e.message}`),
      );
  }
  if (source === 'live') {
    viewer.startLive(config.url || '/live');
    return Promise.resolve();
  }
  viewer.fail(`unknown replay source '${source}' in the page's configuration`);
  return Promise.resolve();
}

const viewer = new Viewer();
const ready = new Promise((resolve) => {
  // let the page paint "loading" before a long decode
  setTimeout(() => start(viewer).then(() => {
    viewer.timing.readyMs = performance.now();
    resolve();
  }, (e) => {
    viewer.fail(String((e && e.message) || e));
    resolve();
  }), 0);
});

/// The page's API, for tests and the console.
window.overtakeViewer = {
  ready,
  get replay() { return viewer.replay; },
  get frame() { return viewer.frame; },
  get step() { return viewer.replay && viewer.replay.frames ? viewer.replay.step[viewer.frame] : 0; },
  get playing() { return viewer.playing; },
  get fileName() { return viewer.fileName; },
  seek: (step) => viewer.seek(step),
  seekTime: (t) => viewer.seekTime(t),
  stepBy: (n) => viewer.stepBy(n),
  play: () => viewer.play(),
  pause: () => viewer.pause(),
  setSpeed: (x) => viewer.setSpeed(x),
  follow: () => viewer.follow(),
  load: (bytes, name = 'replay', file = null) => viewer.load(bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes), name, file),
  get scene() { return viewer.scene; },
  get timing() { return { ...viewer.timing }; },
};
