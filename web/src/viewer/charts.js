// Speed, total acceleration, jerk, and the near-miss figures (TTC, headway) against time
// (uPlot), with the limits and thresholds drawn, a playhead linked to the timeline, and
// click-to-seek.
import uPlot from 'uplot';
import 'uplot/dist/uPlot.min.css';

import { clock, MPH_PER_MPS, safetyThresholds } from './format.js';

const AXIS = { stroke: '#8a94a3', grid: { stroke: '#2a3038', width: 1 }, ticks: { stroke: '#2a3038', width: 1 } };
const LIMIT_COLOR = '#ff4d4f';
const HEADWAY_COLOR = '#f5a623';
// The near-miss chart's y axis: TTC and headway that matter are a few seconds; larger ones
// run off the top, and none (Infinity) is a gap, not a huge value.
const SAFETY_TOP_S = 6;
const SAFETY_SERIES = [
  { key: 'ttcAhead', label: 'TTC ahead', color: '#ff5ce1' },
  { key: 'ttcEntering', label: 'TTC entering', color: '#b28dff' },
  { key: 'headway', label: 'time gap', color: '#32c5ff' },
];

// Axis ticks: "m:ss", or "h:mm:ss" from an hour on.
function shortClock(v) {
  const s = Math.max(0, Math.round(v));
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const sec = String(s % 60).padStart(2, '0');
  return h ? `${h}:${String(m).padStart(2, '0')}:${sec}` : `${m}:${sec}`;
}

// A dashed horizontal line at `limit`, named by `text` (if any) at its right end.
function drawLimit(u, limit, color, text) {
  if (!(limit > 0)) return;
  const ctx = u.ctx;
  const px = devicePixelRatio || 1;
  const y = Math.round(u.valToPos(limit, 'y', true)) + 0.5;
  if (y < u.bbox.top || y > u.bbox.top + u.bbox.height) return;
  ctx.save();
  ctx.strokeStyle = color;
  ctx.lineWidth = Math.max(1, px);
  ctx.setLineDash([6 * px, 4 * px]);
  ctx.beginPath();
  ctx.moveTo(u.bbox.left, y);
  ctx.lineTo(u.bbox.left + u.bbox.width, y);
  ctx.stroke();
  if (text) {
    ctx.fillStyle = color;
    ctx.font = `${Math.round(10 * px)}px sans-serif`;
    ctx.textAlign = 'right';
    ctx.textBaseline = 'bottom';
    ctx.fillText(text, u.bbox.left + u.bbox.width - 4 * px, y - 2 * px);
  }
  ctx.restore();
}

function limitLine(limit) {
  return (u) => drawLimit(u, limit, LIMIT_COLOR, '');
}

// The near-miss thresholds: TTC (for both TTCs) and the time gap (the headway's keys).
function thresholdLines(th) {
  return (u) => {
    drawLimit(u, th.ttc, LIMIT_COLOR, `TTC ${th.ttc} s`);
    drawLimit(u, th.headway, HEADWAY_COLOR, `time gap ${th.headway} s`);
  };
}

const secondsValue = (u, v) => (v == null ? '–' : `${v.toFixed(2)} s`);

// A y range that shows the limit with some room, and clips rare spikes at a few times it.
function rangeFor(limit) {
  return (u, dataMin, dataMax) => {
    const lo = Math.min(0, Number.isFinite(dataMin) ? dataMin : 0);
    const top = Number.isFinite(dataMax) ? dataMax : 0;
    const hi = limit > 0 ? Math.max(limit * 1.2, Math.min(top * 1.05, limit * 3)) : Math.max(1, top * 1.05);
    return [lo, hi];
  };
}

/// The four charts. `onSeek(t_s)` is called when a chart is clicked.
export class Charts {
  constructor(root, replay, onSeek) {
    this.root = root;
    this.onSeek = onSeek;
    this.windowS = 0;
    this.plots = [];
    this.playheads = [];
    this.lastCentre = -1;
    this.lastScaleAt = 0;
    this.setReplay(replay);
  }

  setReplay(replay) {
    for (const p of this.plots) p.destroy();
    this.plots = [];
    this.playheads = [];
    this.labels = [];
    this.replay = replay;
    this.speedMph = new Float32Array(0);
    this.safety = SAFETY_SERIES.map(() => []); // seconds, null where there is none
    this.safetyPoints = 0; // values that are not none
    this.filled = 0;
    const lim = replay.limits || {};
    const line = (label, unit, color) => ({
      label, stroke: color, width: 1, points: { show: false }, value: (u, v) => (v == null ? '–' : `${v.toFixed(2)} ${unit}`),
    });
    const th = safetyThresholds(replay.report);
    const specs = [
      { el: 'chart-speed', title: `Speed (mph), limit ${((lim.speed_mps || 0) * MPH_PER_MPS).toFixed(0)}`, label: 'speed',
        series: [line('speed', 'mph', '#4fb3ff')], range: rangeFor((lim.speed_mps || 0) * MPH_PER_MPS), draw: limitLine((lim.speed_mps || 0) * MPH_PER_MPS) },
      { el: 'chart-acc', title: `Total acceleration (m/s²), limit ${lim.acceleration_mps2 ?? '–'}`, label: 'acceleration',
        series: [line('acceleration', 'm/s²', '#3ddc84')], range: rangeFor(lim.acceleration_mps2 || 0), draw: limitLine(lim.acceleration_mps2 || 0) },
      { el: 'chart-jerk', title: `Jerk (m/s³), limit ${lim.jerk_mps3 ?? '–'}`, label: 'jerk',
        series: [line('jerk', 'm/s³', '#f5a623')], range: rangeFor(lim.jerk_mps3 || 0), draw: limitLine(lim.jerk_mps3 || 0) },
      { el: 'chart-safety', label: 'safety',
        // a replay from before TTC and headway were recorded has none: say so in the title; the
        // headway is the bumper-to-bumper time gap to the car ahead
        title: replay.safetyFrames === 0 && replay.frames > 0 ? 'TTC and time gap: not in this replay' : 'TTC and time gap (s)',
        series: SAFETY_SERIES.map((s) => ({ label: s.label, stroke: s.color, width: 1, points: { show: false }, value: secondsValue })),
        range: [0, SAFETY_TOP_S], draw: thresholdLines(th) },
    ];
    const width = this._width();
    for (const s of specs) {
      const el = this.root.querySelector(`#${s.el}`);
      if (!el) continue;
      el.textContent = '';
      const opts = {
        title: s.title,
        width,
        height: 150,
        pxAlign: 0,
        scales: { x: { time: false }, y: { range: s.range } },
        axes: [
          { ...AXIS, size: 28, values: (u, vals) => vals.map((v) => shortClock(v)) },
          { ...AXIS, size: 44 },
        ],
        series: [
          { label: 't', value: (u, v) => (v == null ? '–' : clock(v)) },
          ...s.series,
        ],
        cursor: { sync: { key: 'overtake-charts' }, drag: { x: false, y: false, setScale: false }, points: { size: 5 } },
        legend: { show: true, live: true },
        hooks: { draw: [s.draw], setScale: [() => this._placeHeads()] },
      };
      const plot = new uPlot(opts, this._data(s.label), el);
      const head = document.createElement('div');
      head.className = 'playhead';
      plot.over.appendChild(head);
      plot.over.addEventListener('click', (e) => {
        const t = plot.posToVal(e.offsetX, 'x');
        if (Number.isFinite(t)) this.onSeek(t);
      });
      this.plots.push(plot);
      this.playheads.push(head);
      this.labels.push(s.label);
    }
    this._markSafety();
  }

  // The near-miss chart's element says how many values it shows (for tests and the console).
  _markSafety() {
    const el = this.root.querySelector('#chart-safety');
    if (el) el.dataset.points = String(this.safetyPoints);
  }

  _width() {
    return Math.max(240, Math.floor(this.root.clientWidth - 12));
  }

  _fill() {
    const r = this.replay;
    if (this.speedMph.length < r.frames) {
      const next = new Float32Array(Math.max(r.frames, this.speedMph.length * 2));
      next.set(this.speedMph.subarray(0, this.filled));
      this.speedMph = next;
    }
    for (let i = this.filled; i < r.frames; ++i) this.speedMph[i] = r.egoSpeed[i] * MPH_PER_MPS;
    // uPlot leaves a gap at null (not at NaN or Infinity): plain arrays with null for none
    SAFETY_SERIES.forEach((s, j) => {
      const col = r[s.key];
      const out = this.safety[j];
      for (let i = this.filled; i < r.frames; ++i) {
        const v = col[i];
        if (Number.isFinite(v)) {
          out.push(v);
          this.safetyPoints += 1;
        } else {
          out.push(null);
        }
      }
    });
    this.filled = r.frames;
  }

  _data(label) {
    const r = this.replay;
    this._fill();
    const n = r.frames;
    const x = r.time.subarray(0, n);
    if (label === 'speed') return [x, this.speedMph.subarray(0, n)];
    if (label === 'acceleration') return [x, r.accTotal.subarray(0, n)];
    if (label === 'safety') return [x, ...this.safety];
    return [x, r.jerk.subarray(0, n)];
  }

  /// New frames arrived (live): redraw with all of them.
  refresh() {
    this.plots.forEach((p, k) => p.setData(this._data(this.labels[k]), this.windowS === 0));
    this._markSafety();
    this.lastCentre = -1;
  }

  /// Shows the whole run, or a window of `seconds` around the playhead.
  setWindow(seconds) {
    this.windowS = seconds;
    this.lastCentre = -1;
    if (seconds === 0) {
      const r = this.replay;
      const n = r.frames;
      if (n > 0) for (const p of this.plots) p.setScale('x', { min: r.time[0], max: r.time[n - 1] });
    }
  }

  /// Moves the playheads to time `t` (seconds), and the window with it.
  setTime(t) {
    this.t = t;
    if (this.windowS > 0) {
      const now = performance.now();
      const w = this.windowS;
      if (this.lastCentre < 0 || Math.abs(t - this.lastCentre) > w * 0.25 || now - this.lastScaleAt > 250) {
        if (t !== this.lastCentre) {
          this.lastCentre = t;
          this.lastScaleAt = now;
          const r = this.replay;
          const t0 = r.frames ? r.time[0] : 0;
          const t1 = r.frames ? r.time[r.frames - 1] : 0;
          let min = t - w * 0.7;
          let max = t + w * 0.3;
          if (min < t0) [min, max] = [t0, t0 + w];
          else if (max > t1 && t1 - w > t0) [min, max] = [t1 - w, t1];
          // uPlot applies a new scale later (a microtask); its setScale hook places the heads
          for (const p of this.plots) p.setScale('x', { min, max });
        }
      }
    }
    this._placeHeads();
  }

  _placeHeads() {
    const t = this.t;
    if (t === undefined) return;
    for (let k = 0; k < this.plots.length; ++k) {
      const p = this.plots[k];
      const left = p.valToPos(t, 'x');
      const head = this.playheads[k];
      const inside = Number.isFinite(left) && left >= 0 && left <= p.over.clientWidth;
      head.style.display = inside ? '' : 'none';
      if (inside) head.style.transform = `translateX(${left.toFixed(1)}px)`;
    }
  }

  resize() {
    const width = this._width();
    for (const p of this.plots) p.setSize({ width, height: 150 });
    this.lastCentre = -1;
  }
}
