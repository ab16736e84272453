// Where things go on the report's charts, as data (no DOM; main.js draws it, the tests read
// it): the speed-against-safety chart's points, error bars and labels, and the labels under
// the bar charts' slots. Labels never overlap: a label goes where it meets no other (trying
// places around its point, further and further out, with a leader line when far); when some
// cannot be placed, every label becomes a number and a legend below the chart names them.
import { ciOf } from './tables.js';

const isNum = (x) => typeof x === 'number' && Number.isFinite(x);
const obj = (x) => (x && typeof x === 'object' && !Array.isArray(x) ? x : {});

/// A box {x, y, w, h} (x, y its top left) overlaps another, `gap` pixels apart counting as
/// overlapping.
export function overlaps(a, b, gap = 0) {
  return a.x < b.x + b.w + gap && b.x < a.x + a.w + gap && a.y < b.y + b.h + gap && b.y < a.y + a.h + gap;
}

/// The pairs of boxes that overlap, as [i, j] (for the tests and the page's own check).
export function overlapping(boxes, gap = 0) {
  const out = [];
  for (let i = 0; i < boxes.length; ++i) {
    for (let j = i + 1; j < boxes.length; ++j) if (boxes[i] && boxes[j] && overlaps(boxes[i], boxes[j], gap)) out.push([i, j]);
  }
  return out;
}

const inside = (b, bounds) => b.x >= bounds.x && b.y >= bounds.y && b.x + b.w <= bounds.x + bounds.w && b.y + b.h <= bounds.y + bounds.h;

/// Round ticks over [lo, hi]: about `count` of them at 1, 2 or 5 times a power of ten.
export function niceTicks(lo, hi, count = 5) {
  if (!(hi > lo)) return { step: 1, ticks: [lo] };
  const raw = (hi - lo) / Math.max(1, count);
  const mag = 10 ** Math.floor(Math.log10(raw));
  const step = [1, 2, 2.5, 5, 10].map((m) => m * mag).find((s) => s >= raw) || 10 * mag;
  const ticks = [];
  for (let t = Math.ceil(lo / step - 1e-9) * step; t <= hi + step * 1e-9; t += step) ticks.push(Math.abs(t) < step * 1e-9 ? 0 : t);
  return { step, ticks };
}

// The directions a label tries around its anchor, in order: right, left, up, down, then the
// diagonals, then between them.
const DIRECTIONS = [[1, 0], [-1, 0], [0, -1], [0, 1], [1, -1], [-1, -1], [1, 1], [-1, 1],
  [1, -0.5], [-1, -0.5], [1, 0.5], [-1, 0.5], [0.5, -1], [-0.5, -1], [0.5, 1], [-0.5, 1]];
const DISTANCES = [3, 7, 12, 18, 26, 36, 48, 64, 84, 110, 140, 180];

/// Places a label of w × h pixels near each anchor {x, y, r (the mark's radius)}: for each in
/// turn, the first place around it (DIRECTIONS at growing DISTANCES) inside `bounds` that
/// overlaps no label placed before (`gap` pixels apart), preferring places that cover no
/// `obstacles` (the marks). Returns per anchor {x, y, w, h, leader (true when away from its
/// mark: draw a line to it)} or null when there is no such place.
export function placeLabels(items, { bounds, obstacles = [], gap = 2 }) {
  const placed = [];
  const out = [];
  for (const it of items) {
    let found = null;
    for (const avoidMarks of [true, false]) {
      for (const d of DISTANCES) {
        for (const [dx, dy] of DIRECTIONS) {
          const r = (it.r || 0) + d;
          const cx = it.x + dx * (r + it.w / 2);
          const cy = it.y + dy * (r + it.h / 2);
          const box = { x: cx - it.w / 2, y: cy - it.h / 2, w: it.w, h: it.h };
          if (!inside(box, bounds)) continue;
          if (placed.some((p) => overlaps(box, p, gap))) continue;
          if (avoidMarks && obstacles.some((o) => overlaps(box, o, 0))) continue;
          found = { ...box, leader: d > 12 };
          break;
        }
        if (found) break;
      }
      if (found) break;
    }
    out.push(found);
    if (found) placed.push(found);
  }
  return out;
}

/// The speed-against-safety chart's figures of a summary row: mean speed and at-fault
/// collisions per 100 miles with their intervals; null when the row has no at-fault figure
/// (rows from before collisions were classified, or counted as contacts) or no speed.
/// `oneSided`: the rate had no event, its interval is [0, the one-sided upper bound] (a row
/// of a bench that says how it reached its intervals; an older one's is two-sided).
export function speedSafetyOf(r) {
  const row = obj(r);
  const c = obj(row.collisions);
  if (!isNum(row.mean_speed_mph) || !isNum(c.at_fault_per_100mi)) return null;
  const rateCI = ciOf(c.at_fault_per_100mi_ci);
  return {
    speed: row.mean_speed_mph,
    speedCI: ciOf(row.mean_speed_mph_ci),
    rate: c.at_fault_per_100mi,
    rateCI,
    oneSided: Boolean(rateCI) && c.at_fault_per_100mi === 0 && rateCI[0] === 0 && 'intervals' in row,
    contacts: 'rubric_incidents' in c,
  };
}

/// An `overtake risk` estimate (the report's "risk", one per folder given to bench --risk) as a
/// point of the speed-against-safety chart: its base runs' mean speed (no interval: the bench
/// rows carry the speed's) and its at-fault rate with its interval; null when it lacks them.
export function riskPointOf(e) {
  const r = obj(e);
  if (!isNum(r.mean_speed_mph) || !isNum(r.rate_per_100mi)) return null;
  const rateCI = ciOf(r.ci95_per_100mi);
  return {
    speed: r.mean_speed_mph,
    speedCI: null,
    rate: r.rate_per_100mi,
    rateCI,
    oneSided: Boolean(r.upper_bound_only),
    contacts: true,
    risk: true,
    colorOf: String(r.policy ?? '?'),
  };
}

/// Ticks of a log axis over [lo, hi] (lo > 0): the powers of ten inside, with 2 and 5 times
/// them when fewer than three would show; each with its text ("0.001", "20").
export function logTicks(lo, hi) {
  const text = (v) => (v >= 1 ? String(Math.round(v)) : v.toFixed(Math.max(0, Math.ceil(-Math.log10(v) - 1e-9))));
  const out = [];
  for (const mults of [[1], [1, 2, 5]]) {
    out.length = 0;
    for (let e = Math.floor(Math.log10(lo)); e <= Math.ceil(Math.log10(hi)); ++e) {
      for (const m of mults) {
        const v = m * 10 ** e;
        if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) out.push({ v: Number(v.toPrecision(12)), text: text(Number(v.toPrecision(12))) });
      }
    }
    if (out.length >= 3) break;
  }
  return out;
}

/// The points no other beats on both figures (another as fast or faster at no more risk, and
/// better on one), in order of rate.
export function paretoOf(points) {
  const beats = (a, b) => a.rate <= b.rate && a.speed >= b.speed && (a.rate < b.rate || a.speed > b.speed);
  return points.filter((p) => !points.some((q) => q !== p && beats(q, p))).sort((a, b) => a.rate - b.rate || a.speed - b.speed);
}

/// The marks' shapes, one per traffic profile.
export const SHAPES = ['circle', 'square', 'triangle', 'diamond', 'down', 'cross'];

const PAD = { left: 58, right: 18, top: 14, bottom: 44 };
const MARK_R = 5;

/// The speed-against-safety chart laid out on `width` × `height` pixels: at-fault collisions
/// per 100 miles across (0 at the left: safer is left), mean speed up (faster is up). One point
/// per row that has both figures, its shape by traffic profile (`traffic`, in order) and colour
/// index by policy (`policies`); an error bar per interval, across for the rate and up for the
/// speed (a rate with no event: a one-sided bar from 0 to its bound); a label per point, by
/// name, or numbered (with `legend`) when the names cannot all be placed apart. `measure(text)`
/// gives a label's width in pixels; `labelHeight` its height. `risk`: `overtake risk`
/// estimates (riskPointOf), drawn as hollow marks labelled by their own names and coloured as
/// their policy; with any, the rate axis is logarithmic (a rate of 0 sits at its left end, its
/// bar dashed up to its bound). Of the estimates of one policy (its configurations, the points
/// of a knob), those no other of them beats on both (as fast at no more risk) are joined in
/// order of rate into a curve (`frontiers`, when two or more): what that policy can do at each
/// risk, against which the bench's other planners stand as points.
export function scatterLayout(rows, { width, height, measure, labelHeight = 14, policies = [], traffic = [], risk = [] }) {
  const plot = { x: PAD.left, y: PAD.top, w: Math.max(10, width - PAD.left - PAD.right), h: Math.max(10, height - PAD.top - PAD.bottom) };
  const points = [];
  const left = [];
  const policyOrder = [...policies];
  const trafficOrder = [...traffic];
  for (const r of rows || []) {
    const f = speedSafetyOf(r);
    const policy = String(obj(r).policy ?? '?');
    const tr = String(obj(r).traffic ?? '?');
    if (!f) {
      left.push({ policy, traffic: tr });
      continue;
    }
    if (!policyOrder.includes(policy)) policyOrder.push(policy);
    if (!trafficOrder.includes(tr)) trafficOrder.push(tr);
    points.push({ row: r, policy, traffic: tr, ...f });
  }
  for (const e of risk || []) {
    const f = riskPointOf(e);
    const tr = String(obj(e).traffic ?? '?');
    if (!f) {
      left.push({ policy: String(obj(e).label ?? '?'), traffic: tr });
      continue;
    }
    if (!policyOrder.includes(f.colorOf)) policyOrder.push(f.colorOf);
    if (!trafficOrder.includes(tr)) trafficOrder.push(tr);
    points.push({ row: e, policy: String(obj(e).label ?? f.colorOf), traffic: tr, ...f });
  }
  const log = points.some((p) => p.risk);
  // the domains: the rate from 0, the speed around the points and their intervals
  let xHi = 0;
  let yLo = Infinity;
  let yHi = -Infinity;
  for (const p of points) {
    xHi = Math.max(xHi, p.rate, p.rateCI ? p.rateCI[1] : 0);
    for (const y of [p.speed, ...(p.speedCI || [])]) {
      yLo = Math.min(yLo, y);
      yHi = Math.max(yHi, y);
    }
  }
  if (!(xHi > 0)) xHi = 1;
  xHi *= 1.08;
  if (!Number.isFinite(yLo)) {
    yLo = 0;
    yHi = 1;
  }
  const ypad = Math.max(0.5, (yHi - yLo) * 0.08);
  yLo -= ypad;
  yHi += ypad;
  const yTicks = niceTicks(yLo, yHi, Math.max(2, Math.round(plot.h / 45)));
  let xLo;
  let X;
  let xTicks;
  if (log) {
    // from half the least positive figure to half again the largest: a rate of 0 at the left
    const positive = points.flatMap((p) => [p.rate, ...(p.rateCI || [])]).filter((v) => v > 0);
    xLo = positive.length ? Math.min(...positive) / 2 : 0.001;
    xHi = positive.length ? Math.max(...positive) * 1.5 : 1;
    if (!(xHi > xLo * 1.01)) xHi = xLo * 10;
    const span = Math.log10(xHi) - Math.log10(xLo);
    X = (v) => plot.x + ((Math.log10(Math.max(v, xLo)) - Math.log10(xLo)) / span) * plot.w;
    const ticks = logTicks(xLo, xHi);
    xTicks = { step: 0, ticks: ticks.map((t) => t.v), texts: ticks.map((t) => t.text) };
  } else {
    xTicks = niceTicks(0, xHi, Math.max(2, Math.round(plot.w / 90)));
    // a little room left of 0, so that the marks and bars of rates of 0 stand clear of the axis
    xLo = -0.025 * xHi;
    X = (v) => plot.x + ((v - xLo) / (xHi - xLo)) * plot.w;
  }
  const Y = (v) => plot.y + plot.h - ((v - yLo) / (yHi - yLo)) * plot.h;
  for (const p of points) {
    p.x = X(p.rate);
    p.y = Y(p.speed);
    p.r = MARK_R;
    p.shape = SHAPES[trafficOrder.indexOf(p.traffic) % SHAPES.length];
    p.color = policyOrder.indexOf(p.colorOf ?? p.policy);
    p.hollow = Boolean(p.risk);
    p.xBar = p.rateCI ? { from: X(p.rateCI[0]), to: X(p.rateCI[1]), y: p.y, oneSided: p.oneSided } : null;
    p.yBar = p.speedCI ? { from: Y(p.speedCI[0]), to: Y(p.speedCI[1]), x: p.x } : null;
  }
  // labels: names when they all fit apart, else numbers and a legend
  const marks = points.map((p) => ({ x: p.x - p.r - 1, y: p.y - p.r - 1, w: 2 * p.r + 2, h: 2 * p.r + 2 }));
  const bounds = { x: plot.x + 1, y: plot.y + 1, w: plot.w - 2, h: plot.h - 2 };
  const tryLabels = (texts) => placeLabels(points.map((p, i) => ({ x: p.x, y: p.y, r: p.r, w: Math.ceil(measure(texts[i])) + 4, h: labelHeight })),
    { bounds, obstacles: marks });
  let mode = 'names';
  let texts = points.map((p) => p.policy);
  let boxes = tryLabels(texts);
  if (boxes.some((b) => !b)) {
    mode = 'numbers';
    texts = points.map((_, i) => String(i + 1));
    boxes = tryLabels(texts);
  }
  const labels = points.map((p, i) => (boxes[i] ? { text: texts[i], ...boxes[i], anchor: { x: p.x, y: p.y } } : null));
  return {
    width, height, plot, points, left, mode, labels,
    unplaced: labels.filter((l) => !l).length,
    legend: mode === 'numbers' ? points.map((p, i) => ({ n: i + 1, policy: p.policy, traffic: p.traffic })) : [],
    traffic: trafficOrder.filter((t) => points.some((p) => p.traffic === t)),
    frontiers: policyOrder
      .map((q) => paretoOf(points.filter((p) => p.risk && p.colorOf === q)))
      .filter((ps) => ps.length >= 2)
      .map((ps) => ({ policy: ps[0].colorOf, color: ps[0].color, points: ps.map((p) => ({ x: p.x, y: p.y })) })),
    policies: policyOrder.filter((q) => points.some((p) => !p.risk && p.policy === q)),
    x: { min: xLo, max: xHi, log, ticks: xTicks.ticks.map((v, i) => ({ v, px: X(v), text: xTicks.texts ? xTicks.texts[i] : null })), step: xTicks.step },
    y: { min: yLo, max: yHi, ticks: yTicks.ticks.map((v) => ({ v, px: Y(v) })), step: yTicks.step },
  };
}

/// The labels under a bar chart's slots (centres `centers`, in pixels, at height `top`):
/// each slot's label in lines (policy, traffic) when every label fits apart from its
/// neighbours; else the slots' numbers (1, 2, ...; every k-th when even those would touch) and
/// a legend names them. Returns {mode: 'names' | 'numbers', boxes: [{text, lines, x, y, w, h}]}
/// (a skipped slot has none).
export function slotLabels(labels, centers, { measure, top = 0, lineHeight = 13, gap = 4 }) {
  const n = labels.length;
  if (!n) return { mode: 'names', boxes: [] };
  const spacing = n > 1 ? Math.min(...centers.slice(1).map((c, i) => c - centers[i])) : Infinity;
  const lines = labels.map((l) => String(l).split('\n'));
  const widths = lines.map((ls) => Math.max(...ls.map((t) => measure(t))));
  const fits = widths.every((w, i) => i === 0 || (widths[i - 1] + w) / 2 + gap <= centers[i] - centers[i - 1]);
  if (fits) {
    return {
      mode: 'names',
      boxes: lines.map((ls, i) => ({ text: labels[i], lines: ls, x: centers[i] - widths[i] / 2, y: top, w: widths[i], h: ls.length * lineHeight })),
    };
  }
  const numberWidth = Math.max(...labels.map((_, i) => measure(String(i + 1))));
  const every = Math.max(1, Math.ceil((numberWidth + gap) / Math.max(1e-9, spacing)));
  const boxes = [];
  for (let i = 0; i < n; ++i) {
    if (i % every !== 0) continue;
    const t = String(i + 1);
    const w = measure(t);
    boxes.push({ text: t, lines: [t], slot: i, x: centers[i] - w / 2, y: top, w, h: lineHeight });
  }
  return { mode: 'numbers', boxes, every };
}
