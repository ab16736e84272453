// The report's tables as data: for each table its columns, each a header and a cell function
// of a row giving {text, cls, title}. No DOM here (main.js draws them; the tests read them).
// Every key may be missing (a bench from before intervals, collision classes or near
// misses, or rows the page summarized itself): a missing figure is '–', a missing interval
// leaves the figure alone.
import { INCIDENT_TYPES } from './summary.js';

export const TYPE_LABELS = { collision: 'collision', speeding: 'speeding', max_acceleration: 'max acc', max_jerk: 'max jerk', outside_lane: 'outside lane' };
const DEFAULT_TTC_S = 1.5;
const DEFAULT_HEADWAY_S = 1.0;
const MINUS = '−';

const isNum = (x) => typeof x === 'number' && Number.isFinite(x);

/// x with d decimals, or '–'.
export const fix = (x, d) => (isNum(x) ? x.toFixed(d) : '–');

/// A 95% interval [lo, hi] with numbers at both ends, or null.
export const ciOf = (ci) => (Array.isArray(ci) && ci.length === 2 && isNum(ci[0]) && isNum(ci[1]) ? ci : null);

/// "43.57 (43.1–44.0)": the figure with d decimals, its interval with dci; the figure alone
/// when there is no interval, '–' when there is no figure.
export function withCI(v, ci, d, dci = d) {
  if (!isNum(v)) return '–';
  const c = ciOf(ci);
  return c ? `${v.toFixed(d)} (${c[0].toFixed(dci)}–${c[1].toFixed(dci)})` : v.toFixed(d);
}

/// A signed figure: "+1.20", "−0.35" (a true minus sign), "0.00".
export function signed(v, d) {
  if (!isNum(v)) return '–';
  const t = Math.abs(v).toFixed(d);
  if (Number(t) === 0) return (0).toFixed(d);
  return `${v > 0 ? '+' : MINUS}${t}`;
}

/// A difference with its interval: "+1.46 (+0.90 to +2.01)" (the ends may have either sign,
/// so "to" and not a dash between them).
export function deltaCI(v, ci, d) {
  if (!isNum(v)) return '–';
  const c = ciOf(ci);
  return c ? `${signed(v, d)} (${signed(c[0], d)} to ${signed(c[1], d)})` : signed(v, d);
}

/// A share (0-1) as a percentage.
export const percent = (x, d = 1) => (isNum(x) ? `${(100 * x).toFixed(d)}%` : '–');

const obj = (x) => (x && typeof x === 'object' && !Array.isArray(x) ? x : {});
const cell = (text, cls = '', title = undefined) => ({ text, cls, title });
const num = (text, extra = '', title = undefined) => cell(text, `num${extra ? ` ${extra}` : ''}`, title);
const intervalTitle = (ci, d) => {
  const c = ciOf(ci);
  return c ? `95% interval ${c[0].toFixed(d)}–${c[1].toFixed(d)}` : undefined;
};

/// The near-miss thresholds the rows were measured with (seconds): the first row's, else the
/// defaults.
export function thresholdsOf(rows) {
  for (const r of rows || []) {
    const n = obj(obj(r).near_misses);
    if (isNum(n.ttc_threshold_s) || isNum(n.headway_threshold_s)) {
      return { ttc: isNum(n.ttc_threshold_s) ? n.ttc_threshold_s : DEFAULT_TTC_S, headway: isNum(n.headway_threshold_s) ? n.headway_threshold_s : DEFAULT_HEADWAY_S };
    }
  }
  return { ttc: DEFAULT_TTC_S, headway: DEFAULT_HEADWAY_S };
}

// "ego hit car ahead 2, car cut in 1" from a by-kind count, or '' when there is none.
function kindsText(byKind) {
  return Object.entries(obj(byKind)).filter(([, n]) => isNum(n) && n > 0)
    .map(([k, n]) => `${k.replace(/_/g, ' ')} ${n}`).join(', ');
}

function atFaultCell(r) {
  const c = obj(r.collisions);
  const v = c.at_fault_per_100mi;
  const notes = [];
  if (isNum(c.at_fault) && isNum(c.total)) notes.push(`${c.at_fault} of ${c.total} collisions at fault`);
  const kinds = kindsText(c.by_kind);
  if (kinds) notes.push(`by kind: ${kinds}`);
  return num(withCI(v, c.at_fault_per_100mi_ci, 2), v > 0 ? 'bad' : '', notes.join('; ') || undefined);
}

/// The summary table's columns for these rows: {group, label, cell(row)}; a column's group
/// heads the columns next to it that share it.
export function summaryColumns(rows) {
  const th = thresholdsOf(rows);
  const near = (r) => obj(r.near_misses);
  return [
    { group: '', label: 'policy', cell: (r) => cell(String(r.policy ?? '?')) },
    { group: '', label: 'traffic', cell: (r) => cell(String(r.traffic ?? '?')) },
    { group: '', label: 'runs', cell: (r) => num(fix(r.runs, 0)) },
    { group: '', label: 'miles', cell: (r) => num(fix(r.total_miles, 1)) },
    { group: 'speed', label: 'mean mph (95% CI)', cell: (r) => num(withCI(r.mean_speed_mph, r.mean_speed_mph_ci, 2, 1)) },
    { group: 'incidents per 100 mi', label: 'all (95% CI)',
      cell: (r) => num(withCI(r.incidents_per_100mi, r.incidents_per_100mi_ci, 1), r.incidents_per_100mi > 0 ? 'bad' : '') },
    ...INCIDENT_TYPES.map((k) => ({
      group: 'incidents per 100 mi', label: TYPE_LABELS[k],
      cell: (r) => {
        const v = obj(r.incidents_per_100mi_by_type)[k];
        return num(fix(v, 1), v > 0 ? 'bad' : '', intervalTitle(obj(r.incidents_per_100mi_by_type_ci)[k], 1));
      },
    })),
    { group: 'collisions per 100 mi', label: 'at fault (95% CI)', cell: atFaultCell },
    { group: 'near misses', label: 'per 100 mi (95% CI)', cell: (r) => num(withCI(near(r).per_100mi, near(r).per_100mi_ci, 1), near(r).per_100mi > 0 ? 'bad' : '', isNum(near(r).episodes) ? `${near(r).episodes} episodes` : undefined) },
    { group: 'near misses', label: 'least TTC ahead (s)', cell: (r) => {
      // null with near misses measured: no car ahead was ever closing in
      const n = near(r);
      const v = n.min_ttc_ahead_s;
      return num(isNum(v) ? v.toFixed(2) : (r.near_misses && v === null ? 'none' : '–'), isNum(v) && v < th.ttc ? 'bad' : '');
    } },
    { group: 'near misses', label: `TTC < ${th.ttc} s`, cell: (r) => num(percent(near(r).share_ttc_below, 2)) },
    { group: 'near misses', label: `headway < ${th.headway} s`, cell: (r) => num(percent(near(r).share_headway_below, 2)) },
    { group: 'incident-free mi', label: 'median (95% CI) / worst',
      cell: (r) => num(`${withCI(r.incident_free_miles_median, r.incident_free_miles_median_ci, 2)} / ${fix(r.incident_free_miles_worst, 2)}`) },
    { group: 'peak acc / jerk', label: 'rubric', cell: (r) => num(`${fix(r.peak_acceleration_mps2, 1)} / ${fix(r.peak_jerk_mps3, 1)}`) },
    { group: 'peak acc / jerk', label: 'strict', cell: (r) => num(`${fix(r.peak_strict_acceleration_mps2, 1)} / ${fix(r.peak_strict_jerk_mps3, 1)}`) },
    { group: 'planner µs', label: 'p50 / p99', cell: (r) => num(`${fix(obj(r.timing).planner_p50_us_median, 0)} / ${fix(obj(r.timing).planner_p99_us_worst, 0)}`) },
  ];
}

// The figures whose intervals the precision table shows: its key in a row's "precision",
// what it is, its decimals.
const PRECISION = [
  { key: 'mean_speed_mph', label: 'mean speed (mph)', d: 2 },
  { key: 'incidents_per_100mi', label: 'incidents per 100 mi', d: 1 },
  { key: 'at_fault_collisions_per_100mi', label: 'at-fault collisions per 100 mi', d: 2 },
];

/// True when some row says how precise its figures are (a bench from before does not).
export function hasPrecision(rows) {
  return (rows || []).some((r) => Object.keys(obj(obj(r).precision)).length > 0);
}

/// The precision table's columns: per figure, its interval's half width and the seeds that
/// would halve it.
export function precisionColumns() {
  return [
    { group: '', label: 'policy', cell: (r) => cell(String(r.policy ?? '?')) },
    { group: '', label: 'traffic', cell: (r) => cell(String(r.traffic ?? '?')) },
    { group: '', label: 'runs', cell: (r) => num(fix(r.runs, 0)) },
    ...PRECISION.flatMap((f) => [
      { group: f.label, label: '± half width', cell: (r) => {
        const p = obj(obj(r.precision)[f.key]);
        return num(isNum(p.half_width) ? `± ${p.half_width.toFixed(f.d)}` : '–');
      } },
      { group: f.label, label: 'seeds to halve', cell: (r) => num(fix(obj(obj(r.precision)[f.key]).seeds_to_halve, 0)) },
    ]),
  ];
}

/// The figures of a paired comparison, in the table's order: the key in a pair's "figures",
/// the column group, decimals.
export const PAIR_FIGURES = [
  { key: 'mean_speed_mph', label: 'Δ mean mph', d: 2 },
  { key: 'incidents_per_100mi', label: 'Δ incidents /100 mi', d: 1 },
  { key: 'at_fault_collisions_per_100mi', label: 'Δ at-fault collisions /100 mi', d: 2 },
  { key: 'collisions_per_100mi', label: 'Δ collisions /100 mi', d: 2, optional: true },
  { key: 'near_misses_per_100mi', label: 'Δ near misses /100 mi', d: 1, optional: true },
];

const VERDICTS = new Set(['better', 'worse']);

/// The pairs as an array (none when the data has no "pairs"), each an object.
export function pairsOf(bench) {
  const p = obj(bench).pairs;
  return Array.isArray(p) ? p.filter((x) => x && typeof x === 'object') : [];
}

/// The paired table's columns: traffic, the pair, seeds, then per figure the difference with
/// its interval, the probability that A is better, and the verdict. The figures that no pair
/// has (an older bench) are left out, as are the optional ones (all collisions, near misses)
/// when none has them.
export function pairColumns(pairs) {
  const has = (key) => pairs.some((p) => obj(p.figures)[key] && typeof obj(p.figures)[key] === 'object');
  const figures = PAIR_FIGURES.filter((f) => !f.optional || has(f.key));
  return [
    { group: '', label: 'traffic', cell: (p) => cell(String(p.traffic ?? '?')) },
    { group: '', label: 'A vs B', cell: (p) => cell(`${p.policy ?? '?'} vs ${p.versus ?? '?'}`) },
    { group: '', label: 'seeds', cell: (p) => num(fix(p.seeds, 0)) },
    ...figures.flatMap((f) => {
      const fig = (p) => obj(obj(p.figures)[f.key]);
      const verdict = (p) => (VERDICTS.has(fig(p).verdict) ? fig(p).verdict : '');
      return [
        { group: f.label, label: 'A − B (95% CI)', cell: (p) => {
          const g = fig(p);
          const title = isNum(g.candidate) && isNum(g.base) ? `${p.policy}: ${g.candidate.toFixed(f.d)}, ${p.versus}: ${g.base.toFixed(f.d)}` : undefined;
          return num(deltaCI(g.difference, g.ci, f.d), verdict(p), title);
        } },
        { group: f.label, label: 'P(A better)', cell: (p) => num(fix(fig(p).probability_of_improvement, 2)) },
        { group: f.label, label: 'verdict', cell: (p) => cell(typeof fig(p).verdict === 'string' ? fig(p).verdict : '–', `verdict ${verdict(p)}`.trim()) },
      ];
    }),
  ];
}

/// The group headers of columns: [{label, span}] runs of the same group.
export function groupsOf(columns) {
  const out = [];
  for (const c of columns) {
    const last = out[out.length - 1];
    if (last && last.label === c.group) last.span += 1;
    else out.push({ label: c.group, span: 1 });
  }
  return out;
}
