// The bench report: the summary table with its intervals, how precise they are, the paired
// comparisons of the policies, charts per policy and traffic profile (with error bars), and
// every run with a link to its replay. Data: the bench object (docs/replay.md) in
// #overtake-bench; any key may be missing in a bench from an older build.
import uPlot from 'uplot';
import 'uplot/dist/uPlot.min.css';

import './report.css';
import { groupOf, INCIDENT_TYPES, summarize } from './summary.js';
import {
  ciOf, fix, groupsOf, hasPrecision, pairColumns, pairsOf, precisionColumns, summaryColumns, TYPE_LABELS, withCI,
} from './tables.js';

const BENCH_PLACEHOLDER = ['__OVERTAKE', 'BENCH__'].join('_');
const ERROR_BAR_COLOR = '#e8ecf1';
const TYPE_COLORS = { collision: '#ff4d4f', speeding: '#ff8c1a', max_acceleration: '#ffd000', max_jerk: '#d36bff', outside_lane: '#32c5ff' };
const GROUP_COLORS = ['#4fb3ff', '#3ddc84', '#f5a623', '#ff5ce1', '#b28dff', '#32c5ff', '#ff8c1a', '#9be15d', '#ff6b6b', '#c0c0c0'];
const AXIS = { stroke: '#8a94a3', grid: { stroke: '#2a3038', width: 1 }, ticks: { stroke: '#2a3038', width: 1 } };

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
// column has a group, then the headers, then one row per item (with `dataset(item)`).
function renderTable(table, columns, items, dataset) {
  table.textContent = '';
  const head = el('thead');
  if (columns.some((c) => c.group)) {
    head.append(el('tr', {}, ...groupsOf(columns).map((g) => el('th', { colspan: g.span, class: 'group' }, g.label))));
  }
  head.append(el('tr', {}, ...columns.map((c) => el('th', {}, c.label))));
  table.append(head);
  const body = el('tbody');
  for (const item of items) {
    body.append(el('tr', { dataset: dataset(item) }, ...columns.map((c) => {
      const v = c.cell(item);
      return el('td', { class: v.cls || undefined, title: v.title }, v.text);
    })));
  }
  table.append(body);
}

function renderSummary(rows) {
  renderTable($('summary'), summaryColumns(rows), rows, (r) => ({ policy: r.policy, traffic: r.traffic }));
  $('summary-note').hidden = !rows.some((r) => ciOf(r.mean_speed_mph_ci) || ciOf(r.incidents_per_100mi_ci));
  const precise = hasPrecision(rows);
  $('precision-section').hidden = !precise;
  if (precise) renderTable($('precision'), precisionColumns(), rows, (r) => ({ policy: r.policy, traffic: r.traffic }));
}

// The paired comparisons, grouped by traffic profile (in the order the data gives them).
function renderPairs(pairs) {
  $('pairs-section').hidden = pairs.length === 0;
  if (!pairs.length) return;
  const order = [...new Set(pairs.map((p) => String(p.traffic)))];
  const sorted = order.flatMap((t) => pairs.filter((p) => String(p.traffic) === t));
  renderTable($('pairs'), pairColumns(pairs), sorted, (p) => ({ traffic: p.traffic, policy: p.policy, versus: p.versus }));
}

// A categorical x axis: one slot per summary row.
function categoryAxis(labels) {
  return {
    ...AXIS,
    size: 48,
    space: 10,
    incrs: [1],
    values: (u, vals) => vals.map((v) => (Number.isInteger(v) && labels[v] !== undefined ? labels[v] : '')),
  };
}

function chartWidth(node) {
  return Math.max(300, Math.floor(node.clientWidth || 600));
}

// Error bars: for each slot i with an interval errors[i] = [lo, hi], a vertical line from lo
// to hi with caps, over the bars (a draw hook: uPlot has none of its own). The chart's node
// counts them in data-error-bars.
function errorBars(errors) {
  return (u) => {
    const ctx = u.ctx;
    const px = devicePixelRatio || 1;
    const cap = 5 * px;
    let drawn = 0;
    ctx.save();
    ctx.beginPath();
    ctx.rect(u.bbox.left, u.bbox.top, u.bbox.width, u.bbox.height);
    ctx.clip();
    ctx.strokeStyle = ERROR_BAR_COLOR;
    ctx.lineWidth = 1.5 * px;
    ctx.beginPath();
    errors.forEach((ci, i) => {
      const c = ciOf(ci);
      if (!c) return;
      const x = Math.round(u.valToPos(i, 'x', true)) + 0.5;
      const lo = u.valToPos(c[0], 'y', true);
      const hi = u.valToPos(c[1], 'y', true);
      ctx.moveTo(x, lo);
      ctx.lineTo(x, hi);
      ctx.moveTo(x - cap, lo);
      ctx.lineTo(x + cap, lo);
      ctx.moveTo(x - cap, hi);
      ctx.lineTo(x + cap, hi);
      drawn += 1;
    });
    ctx.stroke();
    ctx.restore();
    u.root.parentElement.dataset.errorBars = String(drawn);
  };
}

/// A bar per label; `errors` (optional) holds an interval per label, drawn as error bars, and
/// the y axis reaches their tops.
function barChart(node, title, labels, series, yLabel, errors = null) {
  const x = labels.map((_, i) => i);
  const bars = uPlot.paths.bars({ size: [0.6, 80], align: 0 });
  const top = Math.max(0, ...(errors || []).map((c) => (ciOf(c) ? c[1] : 0)));
  const opts = {
    title,
    width: chartWidth(node),
    height: 240,
    scales: { x: { time: false, range: [-0.6, labels.length - 0.4] }, y: { range: (u, lo, hi) => [0, Math.max(1e-9, hi, top) * 1.1] } },
    axes: [categoryAxis(labels.map((l) => l.replace(' / ', '\n'))), { ...AXIS, label: yLabel, size: 56 }],
    series: [{ label: 'group', value: (u, v) => (v == null ? '–' : labels[v]) }, ...series.map((s) => ({
      label: s.label, stroke: s.color, fill: `${s.color}cc`, width: 1, paths: bars, points: { show: false },
      value: s.value || ((u, v) => fix(v, 2)),
    }))],
    cursor: { drag: { x: false, y: false }, points: { show: false } },
    legend: { show: true },
    hooks: errors ? { draw: [errorBars(errors)] } : {},
  };
  return new uPlot(opts, [x, ...series.map((s) => s.data)], node);
}

// A rate per 100 miles with its interval in a legend: "1.23 (0.4–2.9)".
const rateValue = (values, cis, d) => (u, v, si, idx) => (idx == null ? '–' : withCI(values[idx], cis[idx], d));

function renderCharts(rows, runs) {
  const labels = rows.map((r) => `${r.policy} / ${r.traffic}`);
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
  plots.push(barChart(box('chart-incidents'), 'Incidents per 100 miles, by type (95% interval of all)', labels, stacked, 'per 100 mi',
    rows.map((r) => r.incidents_per_100mi_ci)));

  // at-fault collisions and near misses per 100 miles, when the rows have them (a bench from
  // before collisions were classified, or near misses measured, has not)
  const rate = (id, title, color, values, cis, d) => {
    const node = $(id);
    node.hidden = !values.some((v) => typeof v === 'number');
    if (node.hidden) return;
    node.textContent = '';
    plots.push(barChart(node, title, labels, [{ label: 'per 100 mi', color, data: values.map((v) => v ?? null), value: rateValue(values, cis, d) }],
      'per 100 mi', cis));
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
  { key: 'fault', label: 'at-fault collisions', num: true, get: (r) => (r.collisions || {}).at_fault, fmt: (v) => fix(v, 0) },
  // a least TTC of null: the run measured none (no car ahead closed in); '–': not measured
  { key: 'ttc', label: 'least TTC ahead s', num: true, get: (r) => (r.safety || {}).min_ttc_ahead_s,
    fmt: (v, r) => (typeof v === 'number' ? fix(v, 2) : r.safety ? 'none' : '–'), absent: Infinity },
  { key: 'ended', label: 'ended early', get: (r) => r.ended_early || '' },
];
const column = (key) => COLUMNS.find((c) => c.key === key);

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
        const bad = (c.key === 'incidents' || c.key === 'fault') && v > 0;
        const td = el('td', { class: `${c.num ? 'num' : ''}${bad ? ' bad' : ''}` }, c.fmt ? c.fmt(v, r) : v ?? '–');
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
  renderSummary(rows);
  renderPairs(pairs);
  let plots = [];
  if (rows.length) plots = renderCharts(rows, runs);
  renderRuns(runs);
  const resize = () => {
    for (const p of plots) p.setSize({ width: chartWidth(p.root.parentElement), height: p.height });
  };
  window.addEventListener('resize', resize);
  root.dataset.state = 'ready';
  root.dataset.runs = String(runs.length);
  window.overtakeReport = { bench, rows, runs, pairs };
}

main();
