// The bench report: the summary table with its intervals, how precise they are, speed against
// safety, the paired comparisons of the policies (a matrix per figure, and the long table),
// charts per policy and traffic profile (with error bars), and every run with a link to its
// replay. Data: the bench object (docs/replay.md) in #overtake-bench; any key may be missing
// in a bench from an older build. Labels on the charts never overlap (layout.js); the page
// keeps the boxes it drew them in (`window.overtakeReport.labelBoxes()`) for the tests.
import uPlot from 'uplot';
import 'uplot/dist/uPlot.min.css';

import './report.css';
import { overlapping, scatterLayout, slotLabels, speedSafetyOf } from './layout.js';
import { groupOf, INCIDENT_TYPES, summarize } from './summary.js';
import {
  ciOf, collisionsNote, countsContacts, fix, groupsOf, hasPrecision, intervalMethodText, matrixColumns, matrixPolicies, oneSidedRates,
  PAIR_FIGURES, pairColumns, pairsOf, pairTraffic, precisionColumns, rateWithCI, rowNotes, summaryColumns, TYPE_LABELS,
  VERDICTS, verdictMethodText, withCI,
} from './tables.js';

const BENCH_PLACEHOLDER = ['__OVERTAKE', 'BENCH__'].join('_');
const ERROR_BAR_COLOR = '#e8ecf1';
const TYPE_COLORS = { collision: '#ff4d4f', speeding: '#ff8c1a', max_acceleration: '#ffd000', max_jerk: '#d36bff', outside_lane: '#32c5ff' };
const GROUP_COLORS = ['#4fb3ff', '#3ddc84', '#f5a623', '#ff5ce1', '#b28dff', '#ff6b6b', '#00e0c6', '#ffe14d', '#9be15d', '#c0c0c0',
  '#ff9d5c', '#8f9cff', '#e07bff', '#7fd4ff', '#d4b483', '#ff4fa0'];
const AXIS = { stroke: '#8a94a3', grid: { stroke: '#2a3038', width: 1 }, ticks: { stroke: '#2a3038', width: 1 } };
const LABEL_FONT = 11; // px: the labels under the bars and beside the points
const TEXT_COLOR = '#c9d1db';
const MUTED_COLOR = '#8a94a3';

// The boxes (CSS pixels, within each chart's canvas) of the labels each chart drew last, by
// chart id: the tests check that none overlaps another.
const LABEL_BOXES = {};

const $ = (id) => document.getElementById(id);

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null) continue;
    if (k === 'class') e.className = v;
    else if (k === 'dataset') Object.assign(e.dataset, v);
    else e.setAttribute(k, v);
  }
  for (const c of children) e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  return e;
}

function readBench() {
  const node = $('overtake-bench');
  const text = node ? node.textContent.trim() : '';
  if (!text || text === BENCH_PLACEHOLDER) return { empty: true };
  return { bench: JSON.parse(text) };
}

function seedsText(seeds) {
  if (!Array.isArray(seeds) || !seeds.length) return '–';
  const s = [...seeds].sort((a, b) => a - b);
  const parts = [];
  let lo = s[0];
  let prev = s[0];
  for (let i = 1; i <= s.length; ++i) {
    if (i < s.length && s[i] === prev + 1) {
      prev = s[i];
      continue;
    }
    parts.push(lo === prev ? `${lo}` : `${lo}-${prev}`);
    if (i < s.length) lo = prev = s[i];
  }
  return parts.join(',');
}

function renderMeta(bench, runs) {
  const prov = (runs[0] && runs[0].provenance) || {};
  const map = bench.map || {};
  const items = [
    ['policies', (bench.policies || []).join(', ')],
    ['traffic', (bench.traffic || []).join(', ')],
    ['seeds', seedsText(bench.seeds)],
    ['minutes per run', bench.minutes],
    ['steps per call', bench.steps_per_call === 0 ? 'random per reply (by seed)' : bench.steps_per_call],
    ['map', map.path ? `${map.path} (${map.hash || ''})` : undefined],
    ['parameters', bench.params_hash],
    ['runs', `${runs.length}${bench.combinations ? ` of ${bench.combinations}` : ''}`],
    ['revision', prov.git_revision],
    ['host', prov.host],
  ].filter(([, v]) => v !== undefined && v !== '' && v !== null);
  const dl = $('meta');
  dl.textContent = '';
  for (const [k, v] of items) dl.append(el('dt', {}, k), el('dd', {}, String(v)));
}

// Fills `table` with `items` as `columns` (tables.js) say: a row of group headers when any
// column has a group, then the headers, then one row per item (with `dataset(item)`), and
// under an item the lines `notes(item)` gives, if any, across the table.
function renderTable(table, columns, items, dataset, notes = null) {
  table.textContent = '';
  const head = el('thead');
  if (columns.some((c) => c.group)) {
    head.append(el('tr', {}, ...groupsOf(columns).map((g) => el('th', { colspan: g.span, class: 'group' }, g.label))));
  }
  head.append(el('tr', {}, ...columns.map((c) => el('th', { title: c.title }, c.label))));
  table.append(head);
  const body = el('tbody');
  for (const item of items) {
    body.append(el('tr', { dataset: dataset(item) }, ...columns.map((c) => {
      const v = c.cell(item);
      return el('td', { class: v.cls || undefined, title: v.title, dataset: v.data }, v.text);
    })));
    const lines = notes ? notes(item) : [];
    if (lines.length) {
      body.append(el('tr', { class: 'notes-row', dataset: dataset(item) },
        el('td', { colspan: columns.length, class: lines.some((l) => l.startsWith('⚠')) ? 'notes warn' : 'notes' }, lines.join('\n'))));
    }
  }
  table.append(body);
}

function renderSummary(rows, verdicts) {
  renderTable($('summary'), summaryColumns(rows), rows, (r) => ({ policy: r.policy, traffic: r.traffic }), rowNotes);
  const intervals = rows.some((r) => ciOf(r.mean_speed_mph_ci) || ciOf(r.incidents_per_100mi_ci));
  const how = intervalMethodText(verdicts);
  const note = $('summary-note');
  note.hidden = !intervals && !rows.some((r) => rowNotes(r).length);
  const collisions = collisionsNote(rows);
  $('summary-collisions').hidden = !collisions;
  $('summary-collisions').textContent = collisions || '';
  if (how) {
    note.textContent = `In brackets: 95% intervals over the seeds (${how}). A rate with no event: 0 (≤ its one-sided 95% upper bound). ` +
      'Collisions are contacts, one per car touched however long (the rubric counts a collision incident for every second of contact). ' +
      'The time gap is bumper to bumper. Hover a cell for more.';
  } else {
    note.textContent = 'In brackets: 95% intervals (bootstrap over the runs for mean speed and incident-free miles, exact Poisson for the rates per 100 miles). ' +
      'The time gap is bumper to bumper. Hover a cell for more.';
  }
  const precise = hasPrecision(rows);
  $('precision-section').hidden = !precise;
  if (precise) renderTable($('precision'), precisionColumns(), rows, (r) => ({ policy: r.policy, traffic: r.traffic }));
}

// The paired comparisons: how the verdicts were reached, a matrix per figure and traffic
// profile (row policy against column policy), then every pair in one table (folded away).
function renderPairs(pairs, bench) {
  $('pairs-section').hidden = pairs.length === 0;
  if (!pairs.length) return;
  const method = verdictMethodText(bench.verdicts);
  $('pairs-method').textContent = method
    ? `Verdicts: ${method}. A cell is the row's policy against the column's: its difference (row − column) and verdict; hover it for the interval, P(row better) with its interval and the adjusted p-value.`
    : 'Verdicts (a bench from before the tests): better or worse when the 95% interval of the difference leaves out 0, without a correction for the many comparisons. Hover a cell for the interval and P(row better).';
  const traffic = pairTraffic(pairs);
  const order = Array.isArray(bench.policies) ? bench.policies : [];
  const box = $('matrices');
  box.textContent = '';
  const has = (key) => pairs.some((p) => (p.figures || {})[key] && typeof p.figures[key] === 'object');
  for (const f of PAIR_FIGURES.filter((x) => !x.optional || has(x.key))) {
    const block = el('div', { class: 'matrix-figure', dataset: { figure: f.key } },
      el('h3', {}, `${f.name[0].toUpperCase()}${f.name.slice(1)} `, el('span', { class: 'muted' }, f.higher ? 'higher is better' : 'lower is better')));
    const grids = el('div', { class: 'matrix-grids' });
    for (const t of traffic) {
      const policies = matrixPolicies(pairs, t, order);
      const table = el('table', { class: 'matrix', dataset: { figure: f.key, traffic: t } });
      renderTable(table, matrixColumns(pairs, f, t, policies), policies, (a) => ({ policy: a }));
      grids.append(el('div', { class: 'matrix-box' }, el('div', { class: 'matrix-title' }, `${t} traffic`), table));
    }
    block.append(grids);
    box.append(block);
  }
  const legend = $('matrix-legend');
  legend.textContent = '';
  for (const [v, m] of Object.entries(VERDICTS)) {
    legend.append(el('span', { class: `m-key m ${m.cls}`, dataset: { verdict: v } }, `${m.mark} ${v === 'better' ? 'row better' : v === 'worse' ? 'row worse' : m.text}`));
  }
  legend.append(el('span', { class: 'm-key m none' }, '– not in both rows'));
  const sorted = traffic.flatMap((t) => pairs.filter((p) => String(p.traffic) === t));
  renderTable($('pairs'), pairColumns(pairs), sorted, (p) => ({ traffic: p.traffic, policy: p.policy, versus: p.versus }));
}

// A categorical x axis: one slot per summary row, its labels drawn by slotLabelHook (uPlot's
// own would overlap with many rows).
function categoryAxis() {
  return { ...AXIS, size: 40, space: 10, incrs: [1], values: (u, vals) => vals.map(() => '') };
}

// The labels under a bar chart's slots: names (policy, traffic) when they fit apart, else
// numbers, named in the legend under the charts (#slot-legend). Records the boxes drawn.
function slotLabelHook(labels, id) {
  return (u) => {
    const ctx = u.ctx;
    const px = devicePixelRatio || 1;
    ctx.save();
    ctx.font = `${LABEL_FONT * px}px system-ui, sans-serif`;
    const measure = (t) => ctx.measureText(t).width / px;
    const centers = labels.map((_, i) => u.valToPos(i, 'x', true) / px);
    const top = (u.bbox.top + u.bbox.height) / px + 6;
    const lay = slotLabels(labels, centers, { measure, top, lineHeight: LABEL_FONT + 2 });
    ctx.fillStyle = TEXT_COLOR;
    ctx.textAlign = 'center';
    ctx.textBaseline = 'top';
    for (const b of lay.boxes) {
      b.lines.forEach((line, j) => ctx.fillText(line, (b.x + b.w / 2) * px, (b.y + j * (LABEL_FONT + 2)) * px));
    }
    ctx.restore();
    LABEL_BOXES[id] = lay.boxes.map(({ text, x, y, w, h }) => ({ text, x, y, w, h }));
    const node = u.root.parentElement;
    node.dataset.labelMode = lay.mode;
    showSlotLegend();
  };
}

// The legend of the bar charts' numbers, shown while some chart numbers its slots.
let slotLegendLabels = [];
function showSlotLegend() {
  const numbered = [...document.querySelectorAll('.chart[data-label-mode="numbers"]')].length > 0;
  const legend = $('slot-legend');
  if (legend.hidden === !numbered && legend.childElementCount === slotLegendLabels.length) return;
  legend.hidden = !numbered;
  legend.textContent = '';
  slotLegendLabels.forEach((l, i) => legend.append(el('span', {}, el('b', {}, String(i + 1)), ` ${l}`)));
}

function chartWidth(node) {
  return Math.max(300, Math.floor(node.clientWidth || 600));
}

// Error bars: for each slot i with an interval errors[i] = [lo, hi], a vertical line from lo
// to hi with caps, over the bars (a draw hook: uPlot has none of its own); where oneSided[i]
// (a rate with no event: [0, its one-sided upper bound]) a dashed line from 0 with a cap at
// the bound only. The chart's node counts them in data-error-bars (and the one-sided ones in
// data-one-sided-bars).
function errorBars(errors, oneSided = []) {
  return (u) => {
    const ctx = u.ctx;
    const px = devicePixelRatio || 1;
    const cap = 5 * px;
    let drawn = 0;
    let single = 0;
    ctx.save();
    ctx.beginPath();
    ctx.rect(u.bbox.left, u.bbox.top, u.bbox.width, u.bbox.height);
    ctx.clip();
    ctx.strokeStyle = ERROR_BAR_COLOR;
    ctx.lineWidth = 1.5 * px;
    errors.forEach((ci, i) => {
      const c = ciOf(ci);
      if (!c) return;
      const x = Math.round(u.valToPos(i, 'x', true)) + 0.5;
      const lo = u.valToPos(c[0], 'y', true);
      const hi = u.valToPos(c[1], 'y', true);
      ctx.beginPath();
      ctx.setLineDash(oneSided[i] ? [4 * px, 3 * px] : []);
      ctx.moveTo(x, lo);
      ctx.lineTo(x, hi);
      ctx.stroke();
      ctx.setLineDash([]);
      ctx.beginPath();
      if (!oneSided[i]) {
        ctx.moveTo(x - cap, lo);
        ctx.lineTo(x + cap, lo);
      }
      ctx.moveTo(x - cap, hi);
      ctx.lineTo(x + cap, hi);
      ctx.stroke();
      drawn += 1;
      if (oneSided[i]) single += 1;
    });
    ctx.restore();
    u.root.parentElement.dataset.errorBars = String(drawn);
    u.root.parentElement.dataset.oneSidedBars = String(single);
  };
}

/// A bar per label; `errors` (optional) holds an interval per label, drawn as error bars
/// (`oneSided` marks those of a rate with no event), and the y axis reaches their tops. The
/// labels under the bars are drawn apart (slotLabelHook).
function barChart(node, title, labels, series, yLabel, errors = null, oneSided = []) {
  const x = labels.map((_, i) => i);
  const bars = uPlot.paths.bars({ size: [0.6, 80], align: 0 });
  const top = Math.max(0, ...(errors || []).map((c) => (ciOf(c) ? c[1] : 0)));
  const opts = {
    title,
    width: chartWidth(node),
    height: 240,
    scales: { x: { time: false, range: [-0.6, labels.length - 0.4] }, y: { range: (u, lo, hi) => [0, Math.max(1e-9, hi, top) * 1.1] } },
    axes: [categoryAxis(), { ...AXIS, label: yLabel, size: 56 }],
    series: [{ label: 'group', value: (u, v) => (v == null ? '–' : labels[v]) }, ...series.map((s) => ({
      label: s.label, stroke: s.color, fill: `${s.color}cc`, width: 1, paths: bars, points: { show: false },
      value: s.value || ((u, v) => fix(v, 2)),
    }))],
    cursor: { drag: { x: false, y: false }, points: { show: false } },
    legend: { show: true },
    hooks: { draw: [...(errors ? [errorBars(errors, oneSided)] : []), slotLabelHook(labels.map((l) => l.replace(' / ', '\n')), node.id)] },
  };
  return new uPlot(opts, [x, ...series.map((s) => s.data)], node);
}

// A rate per 100 miles with its interval in a legend: "1.23 (0.4–2.9)", "0.00 (≤ 0.68)".
const rateValue = (values, cis, d, rows) => (u, v, si, idx) => (idx == null ? '–' : rateWithCI(values[idx], cis[idx], d, oneSidedRates(rows[idx])));

// Whether each rate had no event and so an interval [0, its one-sided upper bound].
const noEvent = (rows, values, cis) => rows.map((r, i) => {
  const c = ciOf(cis[i]);
  return oneSidedRates(r) && values[i] === 0 && Boolean(c) && c[0] === 0;
});

function renderCharts(rows, runs) {
  const labels = rows.map((r) => `${r.policy} / ${r.traffic}`);
  slotLegendLabels = labels;
  const plots = [];
  const box = (id) => {
    const n = $(id);
    n.textContent = '';
    return n;
  };
  const speedCI = rows.map((r) => r.mean_speed_mph_ci);
  const speed = rows.map((r) => r.mean_speed_mph);
  plots.push(barChart(box('chart-speed'), 'Mean speed (mph), with 95% intervals', labels,
    [{ label: 'mean speed', color: '#4fb3ff', data: speed, value: (u, v, si, idx) => (idx == null ? '–' : `${withCI(speed[idx], speedCI[idx], 2)} mph`) }],
    'mph', speedCI));

  // incidents per 100 miles by type, stacked: each series is drawn up to its cumulative sum
  const per = INCIDENT_TYPES.map((k) => rows.map((r) => (r.incidents_per_100mi_by_type || {})[k] || 0));
  const cum = [];
  let acc = rows.map(() => 0);
  for (const s of per) {
    acc = acc.map((a, i) => a + s[i]);
    cum.push(acc);
  }
  const stacked = INCIDENT_TYPES.map((k, j) => ({
    label: TYPE_LABELS[k], color: TYPE_COLORS[k], data: cum[j],
    value: (u, v, si, idx) => (idx == null ? '–' : fix(per[j][idx], 1)),
  })).reverse();
  // the interval is of all incidents: its bar stands on the top of the stack
  const allCI = rows.map((r) => r.incidents_per_100mi_ci);
  plots.push(barChart(box('chart-incidents'), 'Incidents per 100 miles, by type (95% interval of all)', labels, stacked, 'per 100 mi',
    allCI, noEvent(rows, rows.map((r) => r.incidents_per_100mi), allCI)));

  // at-fault collisions and near misses per 100 miles, when the rows have them (a bench from
  // before collisions were classified or counted as contacts, or near misses measured, has
  // not); a rate with no event has a one-sided bar from 0
  const rate = (id, title, color, values, cis, d) => {
    const node = $(id);
    node.hidden = !values.some((v) => typeof v === 'number');
    if (node.hidden) return;
    node.textContent = '';
    plots.push(barChart(node, title, labels, [{ label: 'per 100 mi', color, data: values.map((v) => v ?? null), value: rateValue(values, cis, d, rows) }],
      'per 100 mi', cis, noEvent(rows, values, cis)));
  };
  const coll = rows.map((r) => r.collisions || {});
  rate('chart-fault', 'At-fault collisions per 100 miles, with 95% intervals', TYPE_COLORS.collision,
    coll.map((c) => c.at_fault_per_100mi), coll.map((c) => c.at_fault_per_100mi_ci), 2);
  const near = rows.map((r) => r.near_misses || {});
  rate('chart-near', 'Near misses per 100 miles, with 95% intervals', '#ff5ce1',
    near.map((n) => n.per_100mi), near.map((n) => n.per_100mi_ci), 1);

  // incident-free distance: the share of runs whose best incident-free distance is at most x
  const groups = rows.map((r) => runs.filter((run) => {
    const g = groupOf(run);
    return g.policy === r.policy && g.traffic === r.traffic;
  }).map((run) => run.best_incident_free_miles || 0).sort((a, b) => a - b));
  const all = groups.flat();
  const lo = all.length ? Math.min(...all) : 0;
  const hi = all.length ? Math.max(...all) : 1;
  const pad = Math.max(0.01, (hi - lo) * 0.05);
  // one point before the smallest value, where no run is at or below
  const xs = [...new Set([Math.max(0, lo - pad), ...all])].sort((a, b) => a - b);
  const data = [xs, ...groups.map((g) => xs.map((x) => {
    let n = 0;
    while (n < g.length && g[n] <= x) ++n;
    return g.length ? n / g.length : null;
  }))];
  const node = box('chart-free');
  plots.push(new uPlot({
    title: 'Best incident-free distance per run (share of runs at or below)',
    width: chartWidth(node),
    height: 260,
    scales: { x: { time: false, range: [Math.max(0, lo - pad), hi + pad] }, y: { range: [0, 1.02] } },
    axes: [{ ...AXIS, label: 'miles', size: 44 }, { ...AXIS, size: 48, values: (u, v) => v.map((y) => `${Math.round(y * 100)}%`) }],
    series: [{ label: 'miles', value: (u, v) => (v == null ? '–' : fix(v, 2)) },
      ...labels.map((l, i) => ({
        label: l, stroke: GROUP_COLORS[i % GROUP_COLORS.length], width: 2, paths: uPlot.paths.stepped({ align: 1 }),
        points: { show: false }, value: (u, v) => (v == null ? '–' : `${Math.round(v * 100)}%`),
      }))],
    cursor: { drag: { x: true, y: false } },
  }, data, node));
  return plots;
}

// ---- speed against safety -------------------------------------------------------------------

// A mark of `shape` (layout.js SHAPES) of radius r at x, y on ctx.
function drawMark(ctx, shape, x, y, r) {
  ctx.beginPath();
  switch (shape) {
    case 'square': ctx.rect(x - r * 0.9, y - r * 0.9, 1.8 * r, 1.8 * r); break;
    case 'triangle': ctx.moveTo(x, y - 1.15 * r); ctx.lineTo(x + 1.1 * r, y + 0.8 * r); ctx.lineTo(x - 1.1 * r, y + 0.8 * r); ctx.closePath(); break;
    case 'down': ctx.moveTo(x, y + 1.15 * r); ctx.lineTo(x + 1.1 * r, y - 0.8 * r); ctx.lineTo(x - 1.1 * r, y - 0.8 * r); ctx.closePath(); break;
    case 'diamond': ctx.moveTo(x, y - 1.2 * r); ctx.lineTo(x + 1.2 * r, y); ctx.lineTo(x, y + 1.2 * r); ctx.lineTo(x - 1.2 * r, y); ctx.closePath(); break;
    case 'cross': ctx.rect(x - r, y - 0.35 * r, 2 * r, 0.7 * r); ctx.rect(x - 0.35 * r, y - r, 0.7 * r, 2 * r); break;
    default: ctx.arc(x, y, r, 0, 2 * Math.PI);
  }
  ctx.fill();
  ctx.stroke();
}

// The same shapes as text, for the legend.
const SHAPE_GLYPHS = { circle: '●', square: '■', triangle: '▲', diamond: '◆', down: '▼', cross: '✚' };

const fmtTick = (v, step) => v.toFixed(Math.max(0, -Math.floor(Math.log10(step) + 1e-9)));

// The speed-against-safety chart: a canvas (drawn from scatterLayout), its legend (shapes for
// the traffic profiles, colours for the policies; numbers when the names did not fit apart),
// the rows left out, and a tooltip on hover. Returns {setSize, height, root} as a uPlot does,
// for the page's resize.
function renderScatter(node, rows, bench) {
  node.textContent = '';
  const withFigures = rows.filter((r) => speedSafetyOf(r));
  node.hidden = rows.length === 0;
  const title = el('div', { class: 'chart-title' }, 'Speed against safety: mean speed and at-fault collisions per 100 miles, with 95% intervals both ways');
  const better = el('div', { class: 'note' }, 'Better is up (faster) and to the left (fewer at-fault collisions). A rate with no event: a dashed bar from 0 to its one-sided 95% upper bound.');
  const canvas = el('canvas', { class: 'scatter', 'aria-label': 'mean speed against at-fault collisions per 100 miles, per policy and traffic profile' });
  const tip = el('div', { class: 'tip', hidden: '' });
  const wrap = el('div', { class: 'scatter-wrap' }, canvas, tip);
  const legend = el('div', { class: 'scatter-legend' });
  const numbers = el('div', { class: 'scatter-numbers', hidden: '' });
  const leftOut = el('div', { class: 'note left-out', hidden: '' });
  node.append(title, better, wrap, legend, numbers, leftOut);
  const policies = Array.isArray(bench.policies) ? bench.policies : [];
  const traffic = Array.isArray(bench.traffic) ? bench.traffic : [];
  const risk = Array.isArray(bench.risk) ? bench.risk : [];
  if (risk.length) {
    better.textContent += ' Hollow marks: `overtake risk` estimates (their base runs\' mean speed, their rate and interval); the rate axis is then logarithmic, a rate of 0 at its left end.';
  }
  const height = 400;
  let lay = null;
  const draw = (width) => {
    const px = devicePixelRatio || 1;
    canvas.width = Math.round(width * px);
    canvas.height = Math.round(height * px);
    canvas.style.width = `${width}px`;
    canvas.style.height = `${height}px`;
    const ctx = canvas.getContext('2d');
    ctx.setTransform(px, 0, 0, px, 0, 0);
    ctx.clearRect(0, 0, width, height);
    ctx.font = `${LABEL_FONT}px system-ui, sans-serif`;
    lay = scatterLayout(rows, { width, height, measure: (t) => ctx.measureText(t).width, labelHeight: LABEL_FONT + 3, policies, traffic, risk });
    const { plot } = lay;
    // grid, ticks, axis titles
    ctx.strokeStyle = '#2a3038';
    ctx.lineWidth = 1;
    ctx.fillStyle = MUTED_COLOR;
    ctx.textBaseline = 'top';
    ctx.textAlign = 'center';
    for (const t of lay.x.ticks) {
      ctx.beginPath();
      ctx.moveTo(Math.round(t.px) + 0.5, plot.y);
      ctx.lineTo(Math.round(t.px) + 0.5, plot.y + plot.h);
      ctx.stroke();
      ctx.fillText(t.text ?? fmtTick(t.v, lay.x.step), t.px, plot.y + plot.h + 5);
    }
    ctx.textAlign = 'right';
    ctx.textBaseline = 'middle';
    for (const t of lay.y.ticks) {
      ctx.beginPath();
      ctx.moveTo(plot.x, Math.round(t.px) + 0.5);
      ctx.lineTo(plot.x + plot.w, Math.round(t.px) + 0.5);
      ctx.stroke();
      ctx.fillText(fmtTick(t.v, lay.y.step), plot.x - 6, t.px);
    }
    ctx.strokeStyle = '#3a414c';
    ctx.strokeRect(plot.x + 0.5, plot.y + 0.5, plot.w, plot.h);
    ctx.textAlign = 'center';
    ctx.textBaseline = 'bottom';
    ctx.fillText(`at-fault collisions per 100 mi${lay.x.log ? ', log scale' : ''}  (← safer)`, plot.x + plot.w / 2, height - 4);
    ctx.save();
    ctx.translate(14, plot.y + plot.h / 2);
    ctx.rotate(-Math.PI / 2);
    ctx.textBaseline = 'middle';
    ctx.fillText('mean speed, mph  (faster →)', 0, 0);
    ctx.restore();
    // error bars, then the marks over them, then the labels
    const color = (p) => GROUP_COLORS[p.color % GROUP_COLORS.length];
    let xBars = 0;
    let yBars = 0;
    let oneSided = 0;
    ctx.save();
    ctx.beginPath();
    ctx.rect(plot.x, plot.y, plot.w, plot.h);
    ctx.clip();
    ctx.lineWidth = 1.5;
    for (const p of lay.points) {
      ctx.strokeStyle = `${color(p)}cc`;
      if (p.xBar) {
        const b = p.xBar;
        ctx.setLineDash(b.oneSided ? [4, 3] : []);
        ctx.beginPath();
        ctx.moveTo(b.from, b.y);
        ctx.lineTo(b.to, b.y);
        ctx.stroke();
        ctx.setLineDash([]);
        ctx.beginPath();
        if (!b.oneSided) {
          ctx.moveTo(b.from, b.y - 4);
          ctx.lineTo(b.from, b.y + 4);
        }
        ctx.moveTo(b.to, b.y - 4);
        ctx.lineTo(b.to, b.y + 4);
        ctx.stroke();
        xBars += 1;
        if (b.oneSided) oneSided += 1;
      }
      if (p.yBar) {
        const b = p.yBar;
        ctx.beginPath();
        ctx.moveTo(b.x, b.from);
        ctx.lineTo(b.x, b.to);
        ctx.moveTo(b.x - 4, b.from);
        ctx.lineTo(b.x + 4, b.from);
        ctx.moveTo(b.x - 4, b.to);
        ctx.lineTo(b.x + 4, b.to);
        ctx.stroke();
        yBars += 1;
      }
    }
    ctx.restore();
    ctx.lineWidth = 1.2;
    ctx.strokeStyle = '#0d0f12';
    for (const f of lay.frontiers) { // one policy's estimates, joined in order of rate
      ctx.save();
      ctx.strokeStyle = color(lay.points.find((p) => p.risk && p.colorOf === f.policy));
      ctx.lineWidth = 1.5;
      ctx.setLineDash([5, 3]);
      ctx.beginPath();
      f.points.forEach((q, i) => (i ? ctx.lineTo(q.x, q.y) : ctx.moveTo(q.x, q.y)));
      ctx.stroke();
      ctx.restore();
    }
    for (const p of lay.points) {
      if (p.hollow) { // an `overtake risk` estimate: a ring in its policy's colour
        ctx.save();
        ctx.fillStyle = 'rgb(28, 32, 38)';
        ctx.strokeStyle = color(p);
        ctx.lineWidth = 2;
        drawMark(ctx, p.shape, p.x, p.y, p.r);
        ctx.restore();
        continue;
      }
      ctx.fillStyle = color(p);
      drawMark(ctx, p.shape, p.x, p.y, p.r);
    }
    ctx.textAlign = 'left';
    ctx.textBaseline = 'middle';
    lay.labels.forEach((l, i) => {
      if (!l) return;
      const p = lay.points[i];
      if (l.leader) {
        ctx.strokeStyle = `${color(p)}99`;
        ctx.lineWidth = 1;
        ctx.beginPath();
        ctx.moveTo(p.x, p.y);
        ctx.lineTo(Math.max(l.x, Math.min(p.x, l.x + l.w)), Math.max(l.y, Math.min(p.y, l.y + l.h)));
        ctx.stroke();
      }
      ctx.fillStyle = 'rgba(28, 32, 38, 0.8)'; // the panel's colour, over the bars behind
      ctx.fillRect(l.x, l.y, l.w, l.h);
      ctx.fillStyle = color(p);
      ctx.fillText(l.text, l.x + 2, l.y + l.h / 2);
    });
    LABEL_BOXES[node.id] = lay.labels.filter(Boolean).map(({ text, x, y, w, h }) => ({ text, x, y, w, h }));
    Object.assign(node.dataset, {
      points: String(lay.points.length), riskPoints: String(lay.points.filter((p) => p.risk).length), frontiers: String(lay.frontiers.length), xLog: String(lay.x.log), xBars: String(xBars), yBars: String(yBars), oneSidedBars: String(oneSided),
      labelMode: lay.mode, unplaced: String(lay.unplaced), overlaps: String(overlapping(LABEL_BOXES[node.id]).length),
    });
    // the legend: shapes by traffic, colours by policy; numbers when the names did not fit
    legend.textContent = '';
    for (const t of lay.traffic) {
      const shape = lay.points.find((p) => p.traffic === t).shape;
      legend.append(el('span', { class: 'key' }, el('span', { class: 'glyph' }, SHAPE_GLYPHS[shape] || '●'), ` ${t} traffic`));
    }
    for (const q of lay.policies) {
      const p = lay.points.find((x) => x.policy === q);
      legend.append(el('span', { class: 'key' }, el('span', { class: 'swatch', style: `background:${color(p)}` }), ` ${q}`));
    }
    for (const p of lay.points.filter((x) => x.risk)) {
      legend.append(el('span', { class: 'key' }, el('span', { class: 'glyph', style: `color:${color(p)}` }, '○'), ` ${p.policy}`));
    }
    numbers.hidden = lay.mode !== 'numbers';
    numbers.textContent = '';
    for (const n of lay.legend) numbers.append(el('span', {}, el('b', {}, String(n.n)), ` ${n.policy} / ${n.traffic}`));
    leftOut.hidden = lay.left.length === 0;
    leftOut.textContent = lay.left.length
      ? `Left out, without at-fault collision figures (runs from before collisions were classified or counted as contacts): ${lay.left.map((l) => `${l.policy} / ${l.traffic}`).join(', ')}.`
      : '';
    if (withFigures.some((r) => !countsContacts(r))) {
      leftOut.hidden = false;
      leftOut.textContent += `${leftOut.textContent ? ' ' : ''}Collisions of a bench from before contacts: counted for every second of contact.`;
    }
  };
  // the tooltip: the nearest point within 14 px
  canvas.addEventListener('mousemove', (e) => {
    if (!lay) return;
    const rect = canvas.getBoundingClientRect();
    const mx = e.clientX - rect.left;
    const my = e.clientY - rect.top;
    let best = null;
    let dist = 14;
    for (const p of lay.points) {
      const d = Math.hypot(p.x - mx, p.y - my);
      if (d < dist) {
        dist = d;
        best = p;
      }
    }
    tip.hidden = !best;
    if (!best) return;
    const digits = best.risk ? 4 : 2;
    const over = best.risk ? ` (overtake risk over ${Math.round(best.row.base_miles || 0)} mi)` : '';
    tip.textContent = `${best.policy} / ${best.traffic}: ${withCI(best.speed, best.speedCI, 2)} mph; at fault ${rateWithCI(best.rate, best.rateCI, digits, best.oneSided)} per 100 mi${over}`;
    tip.style.left = `${Math.min(best.x + 12, canvas.clientWidth - 260)}px`;
    tip.style.top = `${best.y + 10}px`;
  });
  canvas.addEventListener('mouseleave', () => { tip.hidden = true; });
  const api = { height, root: wrap, setSize: ({ width }) => draw(width) };
  draw(chartWidth(node));
  return api;
}

// The share of a run's cycles in which its planner left normal planning (0 for a report from
// before plan statuses were kept; null when its planner does not say how it planned: a
// plan_status of null, a planner over the protocol).
function unusualShare(r) {
  if (r.plan_status === null) return null;
  const c = (r.plan_status || {}).cycles || {};
  const total = Number(r.planner_cycles) || 0;
  return total > 0 ? ((Number(c.least_bad) || 0) + (Number(c.fallback) || 0)) / total : 0;
}

const COLUMNS = [
  { key: 'policy', label: 'policy', get: (r) => groupOf(r).policy },
  { key: 'traffic', label: 'traffic', get: (r) => groupOf(r).traffic },
  { key: 'seed', label: 'seed', num: true, get: (r) => (r.config || {}).seed ?? r.seed },
  { key: 'miles', label: 'miles', num: true, get: (r) => r.distance_miles, fmt: (v) => fix(v, 2) },
  { key: 'mph', label: 'mean mph', num: true, get: (r) => r.mean_speed_mph, fmt: (v) => fix(v, 2) },
  { key: 'incidents', label: 'incidents', num: true, get: (r) => INCIDENT_TYPES.reduce((a, k) => a + ((r.incident_counts || {})[k] || 0), 0) },
  { key: 'free', label: 'best incident-free mi', num: true, get: (r) => r.best_incident_free_miles, fmt: (v) => fix(v, 2) },
  { key: 'acc', label: 'peak acc (strict)', num: true, get: (r) => (r.peak || {}).strict_acceleration_mps2, fmt: (v) => fix(v, 1) },
  { key: 'jerk', label: 'peak jerk (strict)', num: true, get: (r) => (r.peak || {}).strict_jerk_mps3, fmt: (v) => fix(v, 1) },
  { key: 'fallback', label: 'least-bad + fallback cycles', num: true, get: (r) => unusualShare(r), fmt: (v) => (v == null ? '–' : `${fix(100 * v, 1)}%`) },
  // collisions as contacts (one per car touched); a run from before contacts counted one per
  // second of contact: its figures as they are, marked
  { key: 'collisions', label: 'collisions (contacts)', num: true, get: (r) => (r.collisions || {}).total, fmt: (v, r) => contactsText(r, v) },
  { key: 'fault', label: 'at-fault collisions', num: true, get: (r) => (r.collisions || {}).at_fault, fmt: (v, r) => contactsText(r, v) },
  // a least TTC of null: the run measured none (no car ahead closed in); '–': not measured
  { key: 'ttc', label: 'least TTC ahead s', num: true, get: (r) => (r.safety || {}).min_ttc_ahead_s,
    fmt: (v, r) => (typeof v === 'number' ? fix(v, 2) : r.safety ? 'none' : '–'), absent: Infinity },
  { key: 'ended', label: 'ended early', get: (r) => r.ended_early || '' },
];
const column = (key) => COLUMNS.find((c) => c.key === key);

// A run's collision count: as it is for a run that counts contacts, with a mark for one from
// before (per second of contact); '–' when it has none.
function contactsText(r, v) {
  if (typeof v !== 'number') return '–';
  return Array.isArray((r.collisions || {}).contacts) ? fix(v, 0) : `${fix(v, 0)}*`;
}

// The hover text of a run's collision counts.
function contactsTitle(r) {
  const c = r.collisions || {};
  if (Array.isArray(c.contacts)) {
    const rubric = typeof c.rubric_incidents === 'number' ? c.rubric_incidents : (r.incident_counts || {}).collision;
    return `${c.total} contacts, ${c.at_fault} at fault; the rubric counted ${rubric ?? '–'} collision incidents (one per second of contact)`;
  }
  return 'counted for every second of contact (a run from before collisions were counted as contacts)';
}

function renderRuns(runs) {
  const table = $('runs');
  const filter = $('runs-filter');
  const state = { key: 'policy', dir: 1 };
  const draw = () => {
    const q = filter.value.trim().toLowerCase();
    const col = COLUMNS.find((c) => c.key === state.key);
    const rows = runs.filter((r) => !q || `${groupOf(r).policy} ${groupOf(r).traffic} ${(r.config || {}).seed}`.toLowerCase().includes(q));
    rows.sort((a, b) => {
      const x = col.get(a);
      const y = col.get(b);
      const c = col.num ? (x ?? col.absent ?? 0) - (y ?? col.absent ?? 0) || 0 : String(x).localeCompare(String(y));
      if (c !== 0) return c * state.dir;
      return ((a.config || {}).seed ?? 0) - ((b.config || {}).seed ?? 0);
    });
    table.textContent = '';
    const head = el('tr', {}, ...COLUMNS.map((c) => {
      const th = el('th', { dataset: { key: c.key }, class: c.num ? 'num sortable' : 'sortable' }, c.label + (c.key === state.key ? (state.dir > 0 ? ' ▲' : ' ▼') : ''));
      th.addEventListener('click', () => {
        state.dir = state.key === c.key ? -state.dir : 1;
        state.key = c.key;
        draw();
      });
      return th;
    }), el('th', {}, 'replay'));
    table.append(el('thead', {}, head));
    const body = el('tbody');
    for (const r of rows) {
      const incidents = column('incidents').get(r);
      const tr = el('tr', { dataset: { seed: column('seed').get(r) } }, ...COLUMNS.map((c) => {
        const v = c.get(r);
        const bad = (c.key === 'incidents' || c.key === 'fault' || c.key === 'collisions') && v > 0;
        const td = el('td', { class: `${c.num ? 'num' : ''}${bad ? ' bad' : ''}` }, c.fmt ? c.fmt(v, r) : v ?? '–');
        if ((c.key === 'collisions' || c.key === 'fault') && r.collisions) td.title = contactsTitle(r);
        if (c.key === 'incidents' && v > 0) {
          td.title = INCIDENT_TYPES.map((k) => `${TYPE_LABELS[k]}: ${(r.incident_counts || {})[k] || 0}`).join(', ');
        }
        return td;
      }));
      const link = typeof r.replay === 'string' && r.replay
        ? el('a', { href: r.replay, class: 'replay-link' }, incidents > 0 ? 'watch the replay' : 'replay')
        : el('span', { class: 'muted' }, '–');
      tr.append(el('td', {}, link));
      body.append(tr);
    }
    table.append(body);
    $('runs-count').textContent = `${rows.length} of ${runs.length} runs`;
  };
  filter.addEventListener('input', draw);
  draw();
}

function main() {
  const root = $('report');
  let parsed;
  try {
    parsed = readBench();
  } catch (e) {
    root.dataset.state = 'error';
    $('error-banner').hidden = false;
    $('error-banner').textContent = `The bench data in this page is not JSON (${e.message}).`;
    return;
  }
  if (parsed.empty) {
    root.dataset.state = 'empty';
    $('error-banner').hidden = false;
    $('error-banner').className = 'warn';
    $('error-banner').textContent = 'No bench data in this page: `overtake bench … --html report.html` writes a report.';
    return;
  }
  const bench = parsed.bench;
  const runs = Array.isArray(bench.runs) ? bench.runs : [];
  const rows = Array.isArray(bench.summary) && bench.summary.length ? bench.summary : summarize(runs, bench.policies, bench.traffic);
  const pairs = pairsOf(bench);
  renderMeta(bench, runs);
  renderSummary(rows, bench.verdicts);
  renderPairs(pairs, bench);
  let plots = [];
  if (rows.length) plots = [renderScatter($('chart-scatter'), rows, bench), ...renderCharts(rows, runs)];
  else $('chart-scatter').hidden = true;
  renderRuns(runs);
  const resize = () => {
    for (const p of plots) p.setSize({ width: chartWidth(p.root.parentElement), height: p.height });
  };
  window.addEventListener('resize', resize);
  root.dataset.state = 'ready';
  root.dataset.runs = String(runs.length);
  window.overtakeReport = { bench, rows, runs, pairs, labelBoxes: () => structuredClone(LABEL_BOXES) };
}

main();
